#include "cosim/coupler/implicit.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace cosim::coupler {

ConvergenceMeasure measure_convergence(const std::vector<FieldBlock>& blocks,
                                       const Eigen::VectorXd& x, const Eigen::VectorXd& h,
                                       double relative) {
  ConvergenceMeasure measure;
  measure.ratios.assign(blocks.size(), 0.0);
  for (std::size_t b = 0; b < blocks.size(); ++b) {
    const auto& block = blocks[b];
    if (block.size == 0) continue;
    const double change =
        (h.segment(block.offset, block.size) - x.segment(block.offset, block.size)).norm();
    const double size = h.segment(block.offset, block.size).norm();
    const double rms = change / std::sqrt(static_cast<double>(block.size));
    const double inf = std::numeric_limits<double>::infinity();
    const double by_relative = relative * size > 0.0 ? change / (relative * size)
                               : change == 0.0       ? 0.0
                                                     : inf;
    const double by_absolute = block.absolute > 0.0 ? rms / block.absolute : rms == 0.0 ? 0.0 : inf;
    double ratio = std::min(by_relative, by_absolute);
    if (!std::isfinite(change)) ratio = inf;  // NaN: never converged
    measure.ratios[b] = ratio;
    if (ratio > 1.0) measure.converged = false;
    if (ratio > measure.worst || measure.worst_field.empty()) {
      measure.worst = std::max(measure.worst, ratio);
      measure.worst_field = block.field + " of " + block.sender;
    }
  }
  return measure;
}

Eigen::VectorXd block_scales(const std::vector<FieldBlock>& blocks,
                             const Eigen::VectorXd& reference) {
  Eigen::VectorXd scales = Eigen::VectorXd::Ones(reference.size());
  for (const auto& block : blocks) {
    if (block.size == 0) continue;
    const double rms = reference.segment(block.offset, block.size).norm() /
                       std::sqrt(static_cast<double>(block.size));
    double scale = std::max(rms, block.absolute);
    if (!(scale > 0.0) || !std::isfinite(scale)) scale = 1.0;
    scales.segment(block.offset, block.size).setConstant(scale);
  }
  return scales;
}

std::vector<Eigen::Index> accelerated_entries(const std::vector<FieldBlock>& blocks) {
  std::vector<Eigen::Index> entries;
  for (const auto& block : blocks) {
    if (!block.accelerated) continue;
    for (Eigen::Index j = 0; j < block.size; ++j) entries.push_back(block.offset + j);
  }
  return entries;
}

}  // namespace cosim::coupler
