// Acceleration of the fixed-point iteration of implicit coupling: within a window the coupled
// solvers are one map x -> H(x) of the exchanged fields (x the fields handed to the solvers,
// H(x) what they answer), and the window is done when x = H(x). Plain iteration x <- H(x)
// diverges for light structures in a dense fluid (the added-mass instability: the map expands
// along the structure's modes); the accelerators below compute the next input from the
// iterates instead. They follow preCICE's documentation of its acceleration schemes:
// - constant under-relaxation: x <- x + omega r, r = H(x) - x;
// - Aitken dynamic relaxation (Irons & Tuck 1969; Kuettler & Wall, Comput. Mech. 43, 2008):
//   omega_k = -omega_{k-1} r_{k-1}.(r_k - r_{k-1}) / |r_k - r_{k-1}|^2;
// - IQN-ILS (Degroote, Bathe & Vierendeels, Comput. Struct. 87, 2009): the inverse Jacobian of
//   the residual is estimated from the differences of the iterates, V = [r_k - r_{k-1}, ...],
//   W = [H_k - H_{k-1}, ...]; alpha solves min |V alpha + r_k| (QR), and x <- H(x_k) + W alpha.
//
// This is numerical post-processing of exchanged fields, an exchange rule of the coupler, not
// physics. The vectors are the caller's (the coupler scales each field before it gets here).
#pragma once

#include <Eigen/Core>
#include <deque>
#include <string>
#include <vector>

namespace cosim::coupler {

enum class AccelerationKind { none, constant, aitken, iqn_ils };

struct AccelerationOptions {
  AccelerationKind kind = AccelerationKind::iqn_ils;
  // Constant: omega. Aitken: omega of the first iteration (at most; it keeps the sign and the
  // smaller magnitude of the previous window's last factor). IQN-ILS: the relaxed first step of a
  // window before any column exists.
  double relaxation = 0.5;
  // IQN-ILS: windows whose columns are kept for the next windows (0: each window starts afresh).
  int reuse_windows = 0;
  // IQN-ILS: a column whose part orthogonal to the newer columns is below filter times its own
  // length is dropped (preCICE's QR2 filter), so the least-squares problem stays well posed.
  double filter = 1e-10;
  // IQN-ILS: at most this many columns (the oldest go first); 0: as many as the vector length.
  int max_columns = 0;
  // Aitken, IQN-ILS: a bounded step (0: unbounded). An update x_next - x longer than max_step
  // times the residual |r| = |H(x) - x| is shortened to that length along its direction: a trust
  // region on the quasi-Newton step (J. Nocedal and S. J. Wright, Numerical Optimization, 2nd
  // ed., Springer 2006, ch. 4: the step is bounded by a radius), the radius set by the plain
  // iteration's step, so that a least-squares fit to noisy differences (a solver whose answer is
  // not smooth in its input) cannot send the solvers an input far from any they answered.
  double max_step = 0.0;
  // Aitken: a factor that comes out zero or negative is replaced by `relaxation`. Where the map's
  // Jacobian has no eigenvalue above 1 (a light structure's added mass makes them negative), the
  // factor that contracts it is positive; a secant through two iterates gives a non-positive one
  // only where the map is not the affine map the secant assumes (a window whose answer is strongly
  // nonlinear, such as a surge striking a light blade), and a step back along the residual then
  // sends the solvers further out. Off: preCICE's plain Aitken, which a map with an eigenvalue
  // above 1 needs (its fixed point lies behind the iterate).
  bool positive_aitken = false;
};

class Accelerator {
 public:
  explicit Accelerator(AccelerationOptions options);

  // One iteration of the current window: the input `x` given to the solvers and their answer
  // `h` = H(x). Returns the input of the next iteration.
  Eigen::VectorXd next(const Eigen::VectorXd& x, const Eigen::VectorXd& h);
  // The window is done: IQN-ILS keeps its columns for reuse, every scheme starts the next window
  // from its first iteration.
  void end_window();

  const AccelerationOptions& options() const { return options_; }
  // IQN-ILS: columns in use, and columns dropped by the filter so far.
  int columns() const;
  int64_t filtered_columns() const { return filtered_; }
  int64_t bounded_steps() const { return bounded_; }  // updates shortened by max_step so far
  double aitken_factor() const { return omega_; }
  int64_t aitken_restarts() const { return aitken_restarts_; }  // by positive_aitken so far

 private:
  Eigen::VectorXd iqn_step(const Eigen::VectorXd& x, const Eigen::VectorXd& h,
                           const Eigen::VectorXd& r);

  AccelerationOptions options_;
  int iteration_ = 0;  // in the current window
  Eigen::VectorXd previous_r_;
  Eigen::VectorXd previous_h_;
  double omega_ = 0.0;
  // Columns newest first: this window's, then the kept windows' (each window's newest first).
  std::deque<Eigen::VectorXd> v_;
  std::deque<Eigen::VectorXd> w_;
  std::deque<std::pair<std::vector<Eigen::VectorXd>, std::vector<Eigen::VectorXd>>> kept_;
  int64_t filtered_ = 0;
  int64_t aitken_restarts_ = 0;
  int64_t bounded_ = 0;
};

// The name a scenario gives a kind ("none", "constant", "aitken", "iqn-ils").
std::string acceleration_name(AccelerationKind kind);

}  // namespace cosim::coupler
