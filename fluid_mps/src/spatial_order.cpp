#include "cosim/fluid_mps/spatial_order.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>

namespace cosim::mps {
namespace {

// Digits of the least-significant-digit radix sort: 2 048 counters fit in L1.
constexpr int kDigitBits = 11;
constexpr std::uint64_t kDigitMask = (std::uint64_t{1} << kDigitBits) - 1;
// Cells an axis at most: a particle thrown far out only lumps the far cells together (the keys
// stay below 2^60 in 3D), and the order stays a function of the positions.
constexpr std::uint64_t kMostCellsAnAxis = std::uint64_t{1} << 20;

}  // namespace

void order_along_cells(const std::vector<Eigen::Vector3d>& positions, double cell_size,
                       int dimension, std::vector<int>& items, SpatialOrderWork& work) {
  const int m = static_cast<int>(items.size());
  if (m < 2) return;
  // The box and the keys in parallel: minima and maxima are exact in any order, and each key
  // is its item's own.
  const bool parallel = m >= 4096;
  Eigen::Vector3d low = positions[items[0]], high = low;
#pragma omp parallel if (parallel)
  {
    Eigen::Vector3d own_low = low, own_high = high;
#pragma omp for schedule(static) nowait
    for (int t = 0; t < m; ++t) {
      own_low = own_low.cwiseMin(positions[items[t]]);
      own_high = own_high.cwiseMax(positions[items[t]]);
    }
#pragma omp critical
    {
      low = low.cwiseMin(own_low);
      high = high.cwiseMax(own_high);
    }
  }
  // The axes in use, longest first (ties: x before y before z); the first is the slowest.
  std::array<int, 3> axes{0, 1, 2};
  int used = 3;
  if (dimension == 2) {
    axes = {0, 2, 1};
    used = 2;
  }
  const Eigen::Vector3d extent = high - low;
  std::stable_sort(axes.begin(), axes.begin() + used,
                   [&](int a, int b) { return extent[a] > extent[b]; });
  std::array<std::uint64_t, 3> cells{1, 1, 1};
  for (int k = 0; k < used; ++k) {
    const double span = std::floor(extent[axes[k]] / cell_size);
    cells[k] = span < static_cast<double>(kMostCellsAnAxis) ? static_cast<std::uint64_t>(span) + 1
                                                            : kMostCellsAnAxis;
  }
  work.key.resize(m);
#pragma omp parallel for schedule(static) if (parallel)
  for (int t = 0; t < m; ++t) {
    const Eigen::Vector3d& x = positions[items[t]];
    std::uint64_t key = 0;
    for (int k = 0; k < used; ++k) {
      const double c = std::floor((x[axes[k]] - low[axes[k]]) / cell_size);
      const std::uint64_t cell =
          c < static_cast<double>(cells[k] - 1) ? static_cast<std::uint64_t>(c) : cells[k] - 1;
      key = key * cells[k] + cell;
    }
    work.key[t] = key;
  }
  std::uint64_t largest = 1;
  for (int k = 0; k < used; ++k) largest *= cells[k];
  // Stable LSD radix sort on the keys, items alongside; each pass keeps the order of equal
  // digits, so items of one cell keep the order they came in.
  work.key_scratch.resize(m);
  work.item_scratch.resize(m);
  work.count.resize(std::size_t{1} << kDigitBits);
  for (int shift = 0; shift < 64 && (largest - 1) >> shift != 0; shift += kDigitBits) {
    std::fill(work.count.begin(), work.count.end(), 0);
    for (int t = 0; t < m; ++t) ++work.count[(work.key[t] >> shift) & kDigitMask];
    std::exclusive_scan(work.count.begin(), work.count.end(), work.count.begin(), 0);
    for (int t = 0; t < m; ++t) {
      const int slot = work.count[(work.key[t] >> shift) & kDigitMask]++;
      work.key_scratch[slot] = work.key[t];
      work.item_scratch[slot] = items[t];
    }
    work.key.swap(work.key_scratch);
    items.swap(work.item_scratch);
  }
}

}  // namespace cosim::mps
