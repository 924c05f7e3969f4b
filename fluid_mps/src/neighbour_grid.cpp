#include "cosim/fluid_mps/neighbour_grid.hpp"

#include <omp.h>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace cosim::mps {

Eigen::AlignedBox3d bounding_box(const std::vector<Eigen::Vector3d>& positions, int dimension,
                                 double margin, const std::vector<char>* include) {
  Eigen::AlignedBox3d box;  // empty
  for (std::size_t i = 0; i < positions.size(); ++i) {
    if (!include || (*include)[i]) box.extend(positions[i]);
  }
  if (box.isEmpty()) box = Eigen::AlignedBox3d(Eigen::Vector3d::Zero());
  box.min().array() -= margin;
  box.max().array() += margin;
  if (dimension == 2) {
    box.min().z() = -margin;
    box.max().z() = margin;
  }
  return box;
}

NeighbourGrid::NeighbourGrid(int dimension, const Eigen::AlignedBox3d& box, double cell_size,
                             const PeriodicBoundary& periodic)
    : dimension_(dimension), origin_(box.min()), cell_size_(cell_size), periodic_(periodic) {
  if (!(cell_size > 0.0) || box.isEmpty()) {
    throw std::invalid_argument("NeighbourGrid: empty box or non-positive cell size");
  }
  Eigen::Vector3d extent = box.sizes();
  if (periodic_.enabled) {
    // Seam: whole cells over one period (seed 001 section 2.2(4), cells instead of ghosts).
    const double period = periodic_.length();
    const int nx = static_cast<int>(std::floor(period / cell_size * (1.0 + 1e-12)));
    if (nx < 3) {
      throw std::invalid_argument("NeighbourGrid: periodic length below three cell sizes");
    }
    cell_size_ = period / nx;
    origin_.x() = periodic_.x_min;
    extent.x() = period;
  }
  for (int axis = 0; axis < 3; ++axis) {
    const bool flat = axis >= dimension;
    cells_[axis] = flat ? 1 : std::max(1, static_cast<int>(std::ceil(extent[axis] / cell_size_)));
  }
  if (periodic_.enabled) {
    cells_.x() = static_cast<int>(std::lround(extent.x() / cell_size_));
  }
  const double cell_count = static_cast<double>(cells_.x()) * cells_.y() * cells_.z();
  if (cell_count > 2e8) {
    throw std::invalid_argument("NeighbourGrid: domain box too large for the cell size");
  }
}

Eigen::Array3i NeighbourGrid::cell_of(const Eigen::Vector3d& position) const {
  Eigen::Array3i cell(0, 0, 0);
  for (int axis = 0; axis < dimension_; ++axis) {
    const double coordinate = axis == 0 ? periodic_.fold(position.x()) : position[axis];
    const int c = static_cast<int>(std::floor((coordinate - origin_[axis]) / cell_size_));
    cell[axis] = std::clamp(c, 0, cells_[axis] - 1);
  }
  return cell;
}

void NeighbourGrid::x_range(int x, int reach, std::vector<int>& xs) const {
  xs.clear();
  const int nx = cells_.x();
  if (!periodic_.enabled) {
    for (int c = std::max(0, x - reach); c <= std::min(nx - 1, x + reach); ++c) xs.push_back(c);
    return;
  }
  if (2 * reach + 1 >= nx) {
    for (int c = 0; c < nx; ++c) xs.push_back(c);
    return;
  }
  for (int c = x - reach; c <= x + reach; ++c) xs.push_back(((c % nx) + nx) % nx);
  std::sort(xs.begin(), xs.end());
}

int NeighbourGrid::drop_cells() const {
  return periodic_.enabled ? static_cast<int>(std::ceil(std::abs(periodic_.drop) / cell_size_)) : 0;
}

void NeighbourGrid::build(const std::vector<Eigen::Vector3d>& positions,
                          const std::vector<char>* include) {
  const std::size_t cell_count = static_cast<std::size_t>(cells_.x()) * cells_.y() * cells_.z();
  const int n = static_cast<int>(positions.size());
  if (include && include->size() != positions.size()) {
    throw std::invalid_argument("NeighbourGrid::build: include and positions differ in size");
  }
  if (include) {
    included_ = *include;
  } else {
    included_.clear();
  }
  std::vector<std::int64_t> cell_index(n);
#pragma omp parallel for schedule(static) if (n >= 4096)
  for (int i = 0; i < n; ++i) cell_index[i] = linear(cell_of(positions[i]));
  // Counting sort: stable, so particles of one cell stay in index order.
  cell_start_.assign(cell_count + 1, 0);
  auto taken = [&](int i) { return included_.empty() || included_[i] != 0; };
  for (int i = 0; i < n; ++i) {
    if (taken(i)) ++cell_start_[cell_index[i] + 1];
  }
  for (std::size_t c = 0; c < cell_count; ++c) cell_start_[c + 1] += cell_start_[c];
  std::vector<std::int64_t> fill(cell_start_.begin(), cell_start_.end() - 1);
  sorted_.resize(cell_start_[cell_count]);
  for (int i = 0; i < n; ++i) {
    if (taken(i)) sorted_[fill[cell_index[i]]++] = i;
  }
}

template <class Visit>
void NeighbourGrid::visit_cells(const std::vector<int>& xs, const Eigen::Array3i& low,
                                const Eigen::Array3i& high, Visit&& visit) const {
  for (int z = low.z(); z <= high.z(); ++z)
    for (int y = low.y(); y <= high.y(); ++y)
      for (int x : xs) {
        const std::int64_t c = linear(Eigen::Array3i(x, y, z));
        for (std::int64_t k = cell_start_[c]; k < cell_start_[c + 1]; ++k) visit(sorted_[k]);
      }
}

NeighbourList NeighbourGrid::neighbours(const std::vector<Eigen::Vector3d>& positions,
                                        double radius) const {
  if (radius > cell_size_ * (1.0 + 1e-12)) {
    throw std::invalid_argument("NeighbourGrid::neighbours: radius exceeds the cell size");
  }
  const int n = static_cast<int>(positions.size());
  const double radius2 = radius * radius;
  const int drop_cells = this->drop_cells();
  NeighbourList list;
  list.radius = radius;
  list.offset.assign(n + 1, 0);
  auto range = [&](int i, std::vector<int>& xs, Eigen::Array3i& low, Eigen::Array3i& high) {
    const Eigen::Array3i cell = cell_of(positions[i]);
    low = (cell - 1).max(0);
    high = (cell + 1).min(cells_ - 1);
    // Across a seam with a drop, neighbours are stored up to `drop` higher or lower.
    low.y() = std::max(0, low.y() - drop_cells);
    high.y() = std::min(cells_.y() - 1, high.y() + drop_cells);
    x_range(cell.x(), 1, xs);
  };
  auto skipped = [&](int i) { return !included_.empty() && included_[i] == 0; };
  auto distance2 = [&](int i, int j) {
    return periodic_.wrap(positions[j] - positions[i]).squaredNorm();
  };
  // One pass: each thread collects the pairs of a contiguous block of particles in its own
  // buffer, then the blocks are copied in particle order. Each particle's partners come out in
  // the same order whatever the thread count.
  const int max_threads = n >= 4096 ? omp_get_max_threads() : 1;
  std::vector<std::vector<int>> block_index(max_threads);
  std::vector<std::vector<double>> block_distance(max_threads);
  std::vector<int> block_begin(max_threads + 1, n);
#pragma omp parallel num_threads(max_threads) if (n >= 4096)
  {
    const int thread = omp_get_thread_num(), threads = omp_get_num_threads();
    const int begin = static_cast<int>(static_cast<std::int64_t>(n) * thread / threads);
    const int end = static_cast<int>(static_cast<std::int64_t>(n) * (thread + 1) / threads);
    block_begin[thread] = begin;
    std::vector<int>& index = block_index[thread];
    std::vector<double>& distance = block_distance[thread];
    std::vector<int> xs;
    xs.reserve(8);
    for (int i = begin; i < end; ++i) {
      if (skipped(i)) continue;
      Eigen::Array3i low, high;
      range(i, xs, low, high);
      const std::size_t first = index.size();
      visit_cells(xs, low, high, [&](int j) {
        if (j == i) return;
        const double d2 = distance2(i, j);
        if (d2 < radius2) {
          index.push_back(j);
          distance.push_back(std::sqrt(d2));
        }
      });
      list.offset[i + 1] = static_cast<std::int64_t>(index.size() - first);
    }
  }
  for (int i = 0; i < n; ++i) list.offset[i + 1] += list.offset[i];
  list.index.resize(list.offset[n]);
  list.distance.resize(list.offset[n]);
#pragma omp parallel for schedule(static, 1) num_threads(max_threads) if (n >= 4096)
  for (int block = 0; block < max_threads; ++block) {
    if (block_index[block].empty()) continue;
    const std::int64_t at = list.offset[block_begin[block]];
    std::copy(block_index[block].begin(), block_index[block].end(), list.index.begin() + at);
    std::copy(block_distance[block].begin(), block_distance[block].end(),
              list.distance.begin() + at);
  }
  return list;
}

void NeighbourGrid::query(const std::vector<Eigen::Vector3d>& positions,
                          const Eigen::Vector3d& point, double radius,
                          std::vector<int>& found) const {
  found.clear();
  const int reach = static_cast<int>(std::ceil(radius / cell_size_));
  const Eigen::Array3i cell = cell_of(point);
  Eigen::Array3i low = cell, high = cell;
  for (int axis = 0; axis < dimension_; ++axis) {
    const int extra = axis == 1 ? drop_cells() : 0;
    low[axis] = std::max(0, cell[axis] - reach - extra);
    high[axis] = std::min(cells_[axis] - 1, cell[axis] + reach + extra);
  }
  thread_local std::vector<int> xs;  // kept: callers query thousands of points at a time
  x_range(cell.x(), reach, xs);
  const double radius2 = radius * radius;
  visit_cells(xs, low, high, [&](int j) {
    if (periodic_.wrap(positions[j] - point).squaredNorm() < radius2) found.push_back(j);
  });
}

}  // namespace cosim::mps

namespace cosim::mps {

void NeighbourGrid::search_block(const Eigen::Array3i& cell, std::vector<int>& xs,
                                 Eigen::Array3i& low, Eigen::Array3i& high) const {
  const int drop = drop_cells();
  low = (cell - 1).max(0);
  high = (cell + 1).min(cells_ - 1);
  low.y() = std::max(0, low.y() - drop);
  high.y() = std::min(cells_.y() - 1, high.y() + drop);
  x_range(cell.x(), 1, xs);
}

namespace {

// Sorts `candidate` (key << 32 | index, keys distinct) by key, as std::sort sorts the values:
// least-significant-digit radix sort on the key, 8 bits a pass, only as many passes as the
// largest key needs (two below 65 536 particles). In 3D a cell's block holds about 1 300
// candidates, which std::sort took about 2.7 % of a step to order; in 2D about 180, for which
// 11-bit digits spent most of the sort clearing and summing their 2 048 counts.
void sort_by_key(std::vector<std::uint64_t>& candidate, std::vector<std::uint64_t>& buffer,
                 std::uint32_t largest_key) {
  constexpr int kBits = 8;
  constexpr std::uint64_t kMask = (std::uint64_t{1} << kBits) - 1;
  std::array<std::uint32_t, std::size_t{1} << kBits> start;
  buffer.resize(candidate.size());
  for (int bit = 0; bit < 32 && (largest_key >> bit) != 0; bit += kBits) {
    const int shift = 32 + bit;
    start.fill(0);
    for (const std::uint64_t c : candidate) ++start[(c >> shift) & kMask];
    std::uint32_t sum = 0;
    for (std::uint32_t& s : start) {
      const std::uint32_t here = s;
      s = sum;
      sum += here;
    }
    for (const std::uint64_t c : candidate) buffer[start[(c >> shift) & kMask]++] = c;
    candidate.swap(buffer);
  }
}

}  // namespace

// The particles of the 3^D cells around cell c, sorted by key, with their positions.
void NeighbourGrid::gather_candidates(std::int64_t c, const std::vector<Eigen::Vector3d>& positions,
                                      const std::vector<int>& key, KeyedScratch& s) const {
  const Eigen::Array3i cell = cell_at(c);
  Eigen::Array3i low, high;
  search_block(cell, s.xs, low, high);
  s.candidate.clear();
  std::uint32_t largest_key = 0;
  visit_cells(s.xs, low, high, [&](int j) {
    largest_key = std::max(largest_key, static_cast<std::uint32_t>(key[j]));
    s.candidate.push_back(static_cast<std::uint64_t>(key[j]) << 32 | static_cast<std::uint32_t>(j));
  });
  sort_by_key(s.candidate, s.sorted, largest_key);
  const std::size_t count = s.candidate.size();
  s.cx.resize(count);
  s.cy.resize(count);
  s.cz.resize(count);
  s.cj.resize(count);
  s.distance2.resize(count);
  for (std::size_t k = 0; k < count; ++k) {
    s.cj[k] = static_cast<int>(static_cast<std::uint32_t>(s.candidate[k]));
    const Eigen::Vector3d& x = positions[s.cj[k]];
    s.cx[k] = x.x();
    s.cy[k] = x.y();
    s.cz[k] = x.z();
  }
}

// Splits cell c at its centre into 2^D parts and keeps, for each part, the candidates closer
// than sqrt(radius2) to the box of the part's own particles, in key order. A particle then
// tests only its part's candidates and finds the same partners in the same order: the distance
// to the box is never more than the distance to a particle inside it, in floating point too
// (the subtraction, the squares and the sums round monotonically, and the terms are summed as
// candidates_in_reach sums them). In 3D a part's reach holds about 40 % of the 3^3 cells'
// candidates, in 2D about 60 % of the 3^2 cells'. Returns false, to test the whole block, when
// the boundary is periodic (wrapped distances) or the cell holds too few particles to pay.
bool NeighbourGrid::narrow_to_parts(std::int64_t c, const std::vector<Eigen::Vector3d>& positions,
                                    double radius2, KeyedScratch& s) const {
  const int parts = 1 << dimension_;
  const std::int64_t first = cell_start_[c], last = cell_start_[c + 1];
  if (periodic_.enabled || last - first < 2 * parts) return false;
  const Eigen::Array3i cell = cell_at(c);
  const Eigen::Vector3d centre = origin_ + (cell.cast<double>() + 0.5).matrix() * cell_size_;
  constexpr double kInf = std::numeric_limits<double>::infinity();
  std::array<Eigen::Vector3d, 8> low, high;
  low.fill(Eigen::Vector3d::Constant(kInf));
  high.fill(Eigen::Vector3d::Constant(-kInf));
  s.part_of.resize(static_cast<std::size_t>(last - first));
  for (std::int64_t k = first; k < last; ++k) {
    const Eigen::Vector3d& x = positions[sorted_[k]];
    if (!x.allFinite()) return false;  // no box then: the whole block, as without parts
    int part = (x.x() >= centre.x() ? 1 : 0) | (x.y() >= centre.y() ? 2 : 0);
    if (dimension_ == 3 && x.z() >= centre.z()) part |= 4;
    s.part_of[k - first] = static_cast<unsigned char>(part);
    low[part] = low[part].cwiseMin(x);
    high[part] = high[part].cwiseMax(x);
  }
  const std::size_t count = s.cj.size();
  const std::size_t room = count * static_cast<std::size_t>(parts);
  if (s.px.size() < room) {
    s.px.resize(room);
    s.py.resize(room);
    s.pz.resize(room);
    s.pj.resize(room);
  }
  const double *cx = s.cx.data(), *cy = s.cy.data(), *cz = s.cz.data();
  double* d2 = s.distance2.data();
  std::size_t kept = 0;
  for (int part = 0; part < parts; ++part) {
    s.part_begin[part] = kept;
    if (!(low[part].x() <= high[part].x())) continue;  // no particle in this part
    const double lx = low[part].x(), ly = low[part].y(), lz = low[part].z();
    const double hx = high[part].x(), hy = high[part].y(), hz = high[part].z();
    // Per axis at most one of the two gaps is positive (low <= high): their sum is that gap.
    auto gap = [](double below, double above) {
      return (below > 0.0 ? below : 0.0) + (above > 0.0 ? above : 0.0);
    };
#pragma omp simd
    for (std::size_t k = 0; k < count; ++k) {
      const double dx = gap(lx - cx[k], cx[k] - hx);
      const double dy = gap(ly - cy[k], cy[k] - hy);
      const double dz = gap(lz - cz[k], cz[k] - hz);
      d2[k] = (dx * dx + dy * dy) + dz * dz;
    }
    for (std::size_t k = 0; k < count; ++k) {  // branch-free: every slot written, kept if near
      s.px[kept] = cx[k];
      s.py[kept] = cy[k];
      s.pz[kept] = cz[k];
      s.pj[kept] = s.cj[k];
      kept += static_cast<std::size_t>(d2[k] < radius2);
    }
  }
  s.part_begin[parts] = kept;
  return true;
}

// Writes the candidates of `span` closer than sqrt(radius2) to xi (particle i itself left out)
// to out, in candidate order; returns how many. `distance2` has room for span.count values.
std::size_t NeighbourGrid::candidates_in_reach(int i, const Eigen::Vector3d& xi, double radius2,
                                               const CandidateSpan& span, double* distance2,
                                               int* out) const {
  const std::size_t count = span.count;
  std::size_t found = 0;
  if (!periodic_.enabled) {
    // Branch-free: every candidate is written, the slot kept only if in reach. The sum of
    // squares in the order of Eigen's squaredNorm, so the pairs are those of neighbours().
    const double x0 = xi.x(), y0 = xi.y(), z0 = xi.z();
    const double *cx = span.x, *cy = span.y, *cz = span.z;
    double* d2 = distance2;
#pragma omp simd
    for (std::size_t k = 0; k < count; ++k) {
      const double dx = cx[k] - x0, dy = cy[k] - y0, dz = cz[k] - z0;
      d2[k] = (dx * dx + dy * dy) + dz * dz;
    }
    for (std::size_t k = 0; k < count; ++k) {
      out[found] = span.j[k];
      found += static_cast<std::size_t>((d2[k] < radius2) & (span.j[k] != i));
    }
    return found;
  }
  for (std::size_t k = 0; k < count; ++k) {
    const Eigen::Vector3d d(span.x[k] - xi.x(), span.y[k] - xi.y(), span.z[k] - xi.z());
    if (span.j[k] != i && periodic_.wrap(d).squaredNorm() < radius2) out[found++] = span.j[k];
  }
  return found;
}

void NeighbourGrid::neighbours_by_key(const std::vector<Eigen::Vector3d>& positions, double radius,
                                      const std::vector<int>& key, NeighbourList& list,
                                      const std::vector<char>* rows,
                                      NeighbourSearchWork* work) const {
  if (rows && rows->size() != positions.size()) {
    throw std::invalid_argument("NeighbourGrid::neighbours_by_key: rows and positions differ");
  }
  auto wants_row = [&](int i) { return rows == nullptr || (*rows)[i] != 0; };
  if (radius > cell_size_ * (1.0 + 1e-12)) {
    throw std::invalid_argument("NeighbourGrid::neighbours_by_key: radius exceeds the cell size");
  }
  const int n = static_cast<int>(positions.size());
  const std::int64_t cell_count = static_cast<std::int64_t>(cell_start_.size()) - 1;
  const double radius2 = radius * radius;
  list.radius = radius;
  list.offset.assign(static_cast<std::size_t>(n) + 1, 0);
  list.distance.clear();
  // Each thread takes a contiguous run of cells holding about 1/threads of the rows (with
  // `rows`, a cell of dummies only is no work: in a long channel the bed's dummies would
  // otherwise tip the split) and collects its pairs in its own buffer; segment[i] is where
  // particle i's partners start there. The split decides only who computes a row, not what.
  const int threads = n >= 4096 ? omp_get_max_threads() : 1;
  NeighbourSearchWork own_work;
  NeighbourSearchWork& w = work ? *work : own_work;
  w.thread_index.resize(std::max<std::size_t>(w.thread_index.size(), threads));
  w.segment.resize(n);
  w.owner.resize(n);
  std::vector<std::int64_t>& segment = w.segment;
  std::vector<int>& owner = w.owner;
  // Rows before each cell (without `rows`, every listed particle has one: cell_start_).
  const std::vector<std::int64_t>* row_start = &cell_start_;
  if (rows) {
    w.wanted_start.assign(static_cast<std::size_t>(cell_count) + 1, 0);
    for (std::int64_t c = 0; c < cell_count; ++c) {
      std::int64_t wanted = 0;
      for (std::int64_t s = cell_start_[c]; s < cell_start_[c + 1]; ++s)
        wanted += static_cast<std::int64_t>(wants_row(sorted_[s]));
      w.wanted_start[c + 1] = w.wanted_start[c] + wanted;
    }
    row_start = &w.wanted_start;
  }
  const std::int64_t listed = row_start->back();
  bool rows_in_order = true;  // one thread found the rows in ascending i: its buffer is the list
#pragma omp parallel num_threads(threads) if (n >= 4096)
  {
    const int thread = omp_get_thread_num(), count = omp_get_num_threads();
    const auto first_cell = [&](int t) {
      const std::int64_t row = listed * t / count;
      return static_cast<std::int64_t>(
          std::lower_bound(row_start->begin(), row_start->end() - 1, row) - row_start->begin());
    };
    const std::int64_t c_begin = first_cell(thread);
    const std::int64_t c_end = thread + 1 == count ? cell_count : first_cell(thread + 1);
    // The buffer's size is its capacity: it only grows (and is zero-filled) when a search
    // finds more pairs than any before; `used` counts the slots of this search.
    std::vector<int>& index = w.thread_index[thread];
    std::size_t used = 0;
    KeyedScratch scratch;
    int last_row = -1;
    for (std::int64_t c = c_begin; c < c_end; ++c) {
      // A cell none of whose particles wants a row of its own is not searched at all.
      if ((*row_start)[c + 1] == (*row_start)[c]) continue;
      gather_candidates(c, positions, key, scratch);
      const bool in_parts = narrow_to_parts(c, positions, radius2, scratch);
      const CandidateSpan block{scratch.cx.data(), scratch.cy.data(), scratch.cz.data(),
                                scratch.cj.data(), scratch.cj.size()};
      for (std::int64_t s = cell_start_[c]; s < cell_start_[c + 1]; ++s) {
        const int i = sorted_[s];
        if (!wants_row(i)) continue;  // an empty row: offset stays 0
        segment[i] = static_cast<std::int64_t>(used);
        owner[i] = thread;
        if (count == 1 && i < last_row) rows_in_order = false;
        last_row = i;
        CandidateSpan span = block;
        if (in_parts) {
          const int part = scratch.part_of[s - cell_start_[c]];
          const std::size_t b = scratch.part_begin[part];
          span = {scratch.px.data() + b, scratch.py.data() + b, scratch.pz.data() + b,
                  scratch.pj.data() + b, scratch.part_begin[part + 1] - b};
        }
        if (used + span.count > index.size()) {
          index.resize(std::max(2 * index.size(), used + span.count));
        }
        const std::size_t found = candidates_in_reach(
            i, positions[i], radius2, span, scratch.distance2.data(), index.data() + used);
        used += found;
        list.offset[i + 1] = static_cast<std::int64_t>(found);
      }
    }
  }
  for (int i = 0; i < n; ++i) list.offset[i + 1] += list.offset[i];
  if (threads == 1 && rows_in_order) {
    // Rows without partners (or without a row) take no slots, so the buffer is the list; the
    // list's old storage becomes the next search's buffer.
    list.index.swap(w.thread_index[0]);
    list.index.resize(list.offset[n]);  // shrinks: nothing is filled
    return;
  }
  list.index.resize(list.offset[n]);
#pragma omp parallel for schedule(static) num_threads(threads) if (n >= 4096)
  for (int i = 0; i < n; ++i) {
    const std::int64_t length = list.offset[i + 1] - list.offset[i];
    if (length == 0) continue;
    const auto from = w.thread_index[owner[i]].begin() + segment[i];
    std::copy(from, from + length, list.index.begin() + list.offset[i]);
  }
}

}  // namespace cosim::mps
