#include "aggregation_preconditioner.hpp"

#include <algorithm>
#include <limits>

#include <omp.h>

namespace cosim::mps {

bool AggregationPreconditioner::setup(const SparseRows& matrix, double strength) {
  invert_diagonal(matrix, inverse_diagonal_);
  build_aggregates(matrix, strength);
  build_coarse_matrix(matrix);
  factor_.compute(coarse_);
  // A pivot at round-off of the largest means a (numerically) singular coarse matrix: the
  // system itself is then only semi-definite, and Jacobi alone is the safe preconditioner.
  factored_ = factor_.info() == Eigen::Success && aggregate_count_ > 0 &&
              factor_.vectorD().minCoeff() > 1e-10 * factor_.vectorD().maxCoeff();
  return factored_;
}

// Greedy aggregation in row order (Vanek et al. 1996, section 4): a row whose strong neighbours
// are all free starts an aggregate with them; a row left over joins the aggregate of its
// strongest strong neighbour; a row with no aggregated strong neighbour starts its own.
void AggregationPreconditioner::build_aggregates(const SparseRows& m, double strength) {
  const int n = m.rows();
  // Every row's threshold first, in parallel (the same values), so that the greedy passes,
  // which are serial, only compare.
  strong_.resize(n);
#pragma omp parallel for schedule(static) if (n >= 4096)
  for (int i = 0; i < n; ++i) {
    double largest = 0.0;
    for (std::int64_t k = m.offset[i]; k < m.offset[i + 1]; ++k) {
      if (m.column[k] != i) largest = std::max(largest, -m.value[k]);
    }
    // A row without a negative off-diagonal entry has no strong neighbour.
    strong_[i] = largest > 0.0 ? strength * largest : std::numeric_limits<double>::infinity();
  }
  const auto threshold = [&](int i) { return strong_[i]; };
  aggregate_.assign(n, -1);
  int count = 0;
  for (int i = 0; i < n; ++i) {
    if (aggregate_[i] >= 0) continue;
    const double strong = threshold(i);
    bool free = true;
    for (std::int64_t k = m.offset[i]; k < m.offset[i + 1]; ++k) {
      const int j = m.column[k];
      if (j != i && -m.value[k] >= strong && aggregate_[j] >= 0) {
        free = false;
        break;
      }
    }
    if (!free) continue;
    aggregate_[i] = count;
    for (std::int64_t k = m.offset[i]; k < m.offset[i + 1]; ++k) {
      if (m.column[k] != i && -m.value[k] >= strong) aggregate_[m.column[k]] = count;
    }
    ++count;
  }
  for (int i = 0; i < n; ++i) {
    if (aggregate_[i] >= 0) continue;
    const double strong = threshold(i);
    int best = -1;
    double best_weight = 0.0;
    for (std::int64_t k = m.offset[i]; k < m.offset[i + 1]; ++k) {
      const int j = m.column[k];
      if (j != i && -m.value[k] >= strong && aggregate_[j] >= 0 && -m.value[k] > best_weight) {
        best_weight = -m.value[k];
        best = aggregate_[j];
      }
    }
    aggregate_[i] = best >= 0 ? best : count++;
  }
  aggregate_count_ = count;
  // Members of each aggregate in row order (a counting sort).
  member_offset_.assign(static_cast<std::size_t>(count) + 1, 0);
  for (int i = 0; i < n; ++i) ++member_offset_[aggregate_[i] + 1];
  for (int a = 0; a < count; ++a) member_offset_[a + 1] += member_offset_[a];
  member_.resize(n);
  member_cursor_.assign(member_offset_.begin(), member_offset_.end() - 1);
  for (int i = 0; i < n; ++i) member_[member_cursor_[aggregate_[i]]++] = i;
}

// A_c = P^T A P: coarse column a sums the rows of its members, each entry into the row of its
// unknown's aggregate, in row and entry order, so each coarse entry has the same bits for any
// thread count; threads take contiguous ranges of aggregates, and the triplets (one per entry)
// give the same matrix in any order.
void AggregationPreconditioner::build_coarse_matrix(const SparseRows& m) {
  const int count = aggregate_count_;
  const int threads = m.rows() >= 4096 ? std::max(1, omp_get_max_threads()) : 1;
  if (static_cast<int>(scratch_.size()) < threads) scratch_.resize(threads);
#pragma omp parallel num_threads(threads)
  {
    const int thread = omp_get_thread_num(), team = omp_get_num_threads();
    Scratch& s = scratch_[thread];
    s.slot_of.assign(count, -1);
    s.lower.clear();
    const int first = static_cast<int>(static_cast<std::int64_t>(count) * thread / team);
    const int last = static_cast<int>(static_cast<std::int64_t>(count) * (thread + 1) / team);
    for (int a = first; a < last; ++a) {
      s.touched.clear();
      s.row_sum.clear();
      for (int t = member_offset_[a]; t < member_offset_[a + 1]; ++t) {
        const int i = member_[t];
        for (std::int64_t k = m.offset[i]; k < m.offset[i + 1]; ++k) {
          const int b = aggregate_[m.column[k]];
          if (b < a) continue;  // the factorisation reads the lower triangle (rows b >= a)
          if (s.slot_of[b] < 0) {
            s.slot_of[b] = static_cast<int>(s.touched.size());
            s.touched.push_back(b);
            s.row_sum.push_back(0.0);
          }
          s.row_sum[s.slot_of[b]] += m.value[k];
        }
      }
      for (std::size_t k = 0; k < s.touched.size(); ++k) {
        s.lower.emplace_back(s.touched[k], a, s.row_sum[k]);
        s.slot_of[s.touched[k]] = -1;
      }
    }
  }
  lower_.clear();
  for (int t = 0; t < threads; ++t) {
    lower_.insert(lower_.end(), scratch_[t].lower.begin(), scratch_[t].lower.end());
  }
  coarse_.resize(count, count);
  coarse_.setFromTriplets(lower_.begin(), lower_.end());
}

void AggregationPreconditioner::apply(const std::vector<double>& r, std::vector<double>& z) {
  const int n = static_cast<int>(r.size());
  z.resize(n);
#pragma omp parallel for schedule(static) if (n >= 4096)
  for (int i = 0; i < n; ++i) z[i] = inverse_diagonal_[i] * r[i];
  if (!factored_) return;
  // P^T r by aggregate: each sum over the members in row order, as a loop over the rows adds.
  coarse_rhs_.resize(aggregate_count_);
#pragma omp parallel for schedule(static) if (n >= 4096)
  for (int a = 0; a < aggregate_count_; ++a) {
    double sum = 0.0;
    for (int t = member_offset_[a]; t < member_offset_[a + 1]; ++t) sum += r[member_[t]];
    coarse_rhs_[a] = sum;
  }
  coarse_solution_ = factor_.solve(coarse_rhs_);
#pragma omp parallel for schedule(static) if (n >= 4096)
  for (int i = 0; i < n; ++i) z[i] += coarse_solution_[aggregate_[i]];
}

}  // namespace cosim::mps
