// Measures of a waving canopy (seed 000 section 4).
#pragma once

#include <Eigen/Core>
#include <vector>

namespace cosim::vegetation {

// Vegetation number density of every node, n_i = sum_{j != i, r_ij < radius} w(r_ij) with the
// MPS weight w = radius / r - 1 (seed 000 eq. 24; the paper takes radius = 7 d_veg).
std::vector<double> vegetation_number_density(const std::vector<Eigen::Vector3d>& positions,
                                              double radius);

// Seed 000 eq. 24: psi_i = (n_i - n0_i) / n0_i, the relative change of the vegetation density
// from the initial state (0 where the initial density is 0).
std::vector<double> vegetation_density_change(const std::vector<double>& density,
                                              const std::vector<double>& initial_density);

// Running extremes of each plant's tip displacement along one direction: the honami amplitude
// is half their difference.
class TipAmplitude {
 public:
  explicit TipAmplitude(int plants = 0) : low_(plants, 1e300), high_(plants, -1e300) {}
  void observe(int plant, double displacement) {
    low_[plant] = std::min(low_[plant], displacement);
    high_[plant] = std::max(high_[plant], displacement);
  }
  double amplitude(int plant) const {
    return high_[plant] >= low_[plant] ? 0.5 * (high_[plant] - low_[plant]) : 0.0;
  }
  double mean_amplitude() const;
  int plants() const { return static_cast<int>(low_.size()); }

 private:
  std::vector<double> low_, high_;
};

}  // namespace cosim::vegetation
