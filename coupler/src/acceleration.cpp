#include "cosim/coupler/acceleration.hpp"

#include <Eigen/QR>
#include <cmath>
#include <stdexcept>

namespace cosim::coupler {

std::string acceleration_name(AccelerationKind kind) {
  switch (kind) {
    case AccelerationKind::none:
      return "none";
    case AccelerationKind::constant:
      return "constant";
    case AccelerationKind::aitken:
      return "aitken";
    case AccelerationKind::iqn_ils:
      return "iqn-ils";
  }
  return "?";
}

Accelerator::Accelerator(AccelerationOptions options)
    : options_(options), omega_(options.relaxation) {
  if (!(options_.relaxation > 0.0 && options_.relaxation <= 1.0)) {
    throw std::invalid_argument("acceleration: relaxation must be in (0, 1]");
  }
}

int Accelerator::columns() const {
  auto count = static_cast<int>(v_.size());
  for (const auto& window : kept_) count += static_cast<int>(window.first.size());
  return count;
}

Eigen::VectorXd Accelerator::next(const Eigen::VectorXd& x, const Eigen::VectorXd& h) {
  if (x.size() != h.size()) throw std::invalid_argument("acceleration: x and H(x) differ in size");
  if (iteration_ > 0 && previous_r_.size() != x.size()) {
    throw std::invalid_argument("acceleration: the coupled fields changed size within a window");
  }
  const Eigen::VectorXd r = h - x;
  Eigen::VectorXd next;
  switch (options_.kind) {
    case AccelerationKind::none:
      next = h;
      break;
    case AccelerationKind::constant:
      next = x + options_.relaxation * r;
      break;
    case AccelerationKind::aitken:
      if (iteration_ == 0) {
        // As preCICE: a new window starts from the smaller of the initial factor and the last.
        omega_ = std::copysign(std::min(options_.relaxation, std::abs(omega_)), omega_);
      } else {
        const Eigen::VectorXd dr = r - previous_r_;
        const double dr2 = dr.squaredNorm();
        // dr = 0: the residual did not change (already converged or a flat map); keep omega.
        if (dr2 > 0.0) omega_ = -omega_ * previous_r_.dot(dr) / dr2;
        if (options_.positive_aitken && !(omega_ > 0.0)) {
          omega_ = options_.relaxation;
          ++aitken_restarts_;
        }
      }
      next = x + omega_ * r;
      break;
    case AccelerationKind::iqn_ils:
      next = iqn_step(x, h, r);
      break;
  }
  const bool bounded =
      options_.kind == AccelerationKind::aitken || options_.kind == AccelerationKind::iqn_ils;
  if (bounded && options_.max_step > 0.0) {
    const double step = (next - x).norm(), radius = options_.max_step * r.norm();
    if (step > radius) {
      next = x + (radius / step) * (next - x);
      ++bounded_;
    }
  }
  previous_r_ = r;
  previous_h_ = h;
  ++iteration_;
  return next;
}

Eigen::VectorXd Accelerator::iqn_step(const Eigen::VectorXd& x, const Eigen::VectorXd& h,
                                      const Eigen::VectorXd& r) {
  if (iteration_ > 0) {
    v_.push_front(r - previous_r_);
    w_.push_front(h - previous_h_);
  }
  // Columns of other vector lengths (a window before the fields changed size) cannot be used.
  std::erase_if(kept_, [&](const auto& window) {
    return !window.first.empty() && window.first.front().size() != x.size();
  });
  const int limit = options_.max_columns > 0 ? options_.max_columns : static_cast<int>(x.size());
  // The oldest columns go first when there are too many.
  while (columns() > limit) {
    if (!kept_.empty()) {
      auto& oldest = kept_.back();
      oldest.first.pop_back();
      oldest.second.pop_back();
      if (oldest.first.empty()) kept_.pop_back();
    } else {
      v_.pop_back();
      w_.pop_back();
    }
  }
  while (true) {
    // Newest first: v_ then each kept window.
    std::vector<const Eigen::VectorXd*> vs;
    std::vector<const Eigen::VectorXd*> ws;
    for (std::size_t i = 0; i < v_.size(); ++i) {
      vs.push_back(&v_[i]);
      ws.push_back(&w_[i]);
    }
    for (const auto& window : kept_) {
      for (std::size_t i = 0; i < window.first.size(); ++i) {
        vs.push_back(&window.first[i]);
        ws.push_back(&window.second[i]);
      }
    }
    if (vs.empty()) return x + options_.relaxation * r;
    const auto n = static_cast<Eigen::Index>(vs.size());
    Eigen::MatrixXd v(x.size(), n);
    Eigen::MatrixXd w(x.size(), n);
    for (Eigen::Index j = 0; j < n; ++j) {
      v.col(j) = *vs[static_cast<std::size_t>(j)];
      w.col(j) = *ws[static_cast<std::size_t>(j)];
    }
    const Eigen::HouseholderQR<Eigen::MatrixXd> qr(v);
    const Eigen::Index rank_limit = std::min(n, x.size());
    const Eigen::MatrixXd upper =
        qr.matrixQR().topLeftCorner(rank_limit, n).triangularView<Eigen::Upper>();
    // QR2 filter: |R_jj| is the length of column j orthogonal to the newer columns 0..j-1.
    // Columns beyond the vector length cannot be independent of the newer ones.
    Eigen::Index drop = n > x.size() ? x.size() : -1;
    for (Eigen::Index j = 0; j < rank_limit && drop < 0; ++j) {
      if (std::abs(upper(j, j)) < options_.filter * v.col(j).norm() || v.col(j).norm() == 0.0) {
        drop = j;
      }
    }
    if (drop >= 0) {
      ++filtered_;
      auto index = static_cast<std::size_t>(drop);
      if (index < v_.size()) {
        v_.erase(v_.begin() + static_cast<std::ptrdiff_t>(index));
        w_.erase(w_.begin() + static_cast<std::ptrdiff_t>(index));
      } else {
        index -= v_.size();
        for (auto it = kept_.begin(); it != kept_.end(); ++it) {
          if (index < it->first.size()) {
            it->first.erase(it->first.begin() + static_cast<std::ptrdiff_t>(index));
            it->second.erase(it->second.begin() + static_cast<std::ptrdiff_t>(index));
            if (it->first.empty()) kept_.erase(it);
            break;
          }
          index -= it->first.size();
        }
      }
      continue;
    }
    // alpha = argmin |V alpha + r|: R alpha = -Q^T r.
    const Eigen::VectorXd qtr = (qr.householderQ().transpose() * r).head(n);
    const Eigen::VectorXd alpha =
        upper.topLeftCorner(n, n).triangularView<Eigen::Upper>().solve(-qtr);
    return h + w * alpha;
  }
}

void Accelerator::end_window() {
  if (options_.kind == AccelerationKind::iqn_ils && options_.reuse_windows > 0 && !v_.empty()) {
    kept_.emplace_front(std::vector<Eigen::VectorXd>(v_.begin(), v_.end()),
                        std::vector<Eigen::VectorXd>(w_.begin(), w_.end()));
    while (static_cast<int>(kept_.size()) > options_.reuse_windows) kept_.pop_back();
  }
  v_.clear();
  w_.clear();
  iteration_ = 0;
}

}  // namespace cosim::coupler
