#include "cosim/vegetation_beam/canopy_metrics.hpp"

#include <cmath>
#include <map>
#include <tuple>

namespace cosim::vegetation {

std::vector<double> vegetation_number_density(const std::vector<Eigen::Vector3d>& positions,
                                              double radius) {
  // Cells of the radius: only the 27 neighbouring cells can hold partners.
  using Cell = std::tuple<long, long, long>;
  auto cell_of = [&](const Eigen::Vector3d& p) {
    return Cell{static_cast<long>(std::floor(p.x() / radius)),
                static_cast<long>(std::floor(p.y() / radius)),
                static_cast<long>(std::floor(p.z() / radius))};
  };
  std::map<Cell, std::vector<int>> cells;
  for (int i = 0; i < static_cast<int>(positions.size()); ++i)
    cells[cell_of(positions[i])].push_back(i);
  std::vector<double> density(positions.size(), 0.0);
  for (int i = 0; i < static_cast<int>(positions.size()); ++i) {
    const auto [cx, cy, cz] = cell_of(positions[i]);
    for (long dx = -1; dx <= 1; ++dx) {
      for (long dy = -1; dy <= 1; ++dy) {
        for (long dz = -1; dz <= 1; ++dz) {
          const auto found = cells.find(Cell{cx + dx, cy + dy, cz + dz});
          if (found == cells.end()) continue;
          for (const int j : found->second) {
            if (j == i) continue;
            const double r = (positions[j] - positions[i]).norm();
            if (r > 0.0 && r < radius) density[i] += radius / r - 1.0;
          }
        }
      }
    }
  }
  return density;
}

std::vector<double> vegetation_density_change(const std::vector<double>& density,
                                              const std::vector<double>& initial_density) {
  std::vector<double> change(density.size(), 0.0);
  for (std::size_t i = 0; i < density.size(); ++i) {
    if (initial_density[i] > 0.0)
      change[i] = (density[i] - initial_density[i]) / initial_density[i];
  }
  return change;
}

double TipAmplitude::mean_amplitude() const {
  if (low_.empty()) return 0.0;
  double sum = 0.0;
  for (int plant = 0; plant < plants(); ++plant) sum += amplitude(plant);
  return sum / plants();
}

}  // namespace cosim::vegetation
