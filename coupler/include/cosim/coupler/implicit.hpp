// The coupler's bookkeeping of implicit coupling: the exchanged fields of one window as one
// vector of blocks (one block per field and solid), the convergence measure of an iteration, and
// the per-block scaling the accelerator works in (fields of different units in one vector).
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

namespace cosim::coupler {

struct FieldBlock {
  std::string sender;     // who publishes the field as H(x)
  std::string field;      // its name there ("drag", "ambient_velocity@vegetation_beam")
  std::string input;      // the name the coupler publishes the next input under
  double absolute = 0.0;  // root-mean-square change below which it counts as converged [its unit]
  // The receiver reads this block in the iterations after the first, so the accelerator
  // relaxes it. A block nobody reads there (a resolved solid's velocities: the flow moves its
  // wall along the positions, exchange::resolved_path) passes on as H(x): relaxing it would only
  // hold back its convergence measure, which is then the change of the sender's answer between
  // iterations.
  bool accelerated = true;
  Eigen::Index offset = 0;
  Eigen::Index size = 0;
};

struct ConvergenceMeasure {
  bool converged = true;
  // Largest over the blocks of min(|r| / (relative |H|), rms(r) / absolute): <= 1 converged.
  double worst = 0.0;
  std::string worst_field;     // "drag of vegetation_beam"
  std::vector<double> ratios;  // each block's min(...) above, in block order (0 for an empty one)
};

// Converged when for every block |H(x) - x|_2 <= relative |H(x)|_2 or the root-mean-square of
// H(x) - x is at most the block's absolute tolerance.
ConvergenceMeasure measure_convergence(const std::vector<FieldBlock>& blocks,
                                       const Eigen::VectorXd& x, const Eigen::VectorXd& h,
                                       double relative);

// Per-block scale: the root-mean-square of `reference` in the block, at least its absolute
// tolerance (a field that is still zero is weighted by its tolerance), so that every field has
// a comparable weight in the accelerator's least-squares problem.
Eigen::VectorXd block_scales(const std::vector<FieldBlock>& blocks,
                             const Eigen::VectorXd& reference);

// The entries of the accelerated blocks, in block order (FieldBlock::accelerated).
std::vector<Eigen::Index> accelerated_entries(const std::vector<FieldBlock>& blocks);

}  // namespace cosim::coupler
