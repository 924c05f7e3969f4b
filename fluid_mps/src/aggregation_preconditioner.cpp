#include "aggregation_preconditioner.hpp"

#include <algorithm>
#include <limits>

#include <omp.h>

namespace cosim::mps {
namespace {

// joined_ codes: a global aggregate (>= 0), none yet, or a stretch's k-th pass-3 aggregate as
// own_code(k) = kFirstOwn - k (own_code is its own inverse).
constexpr int kNoAggregate = -1;
constexpr int kFirstOwn = -2;
constexpr int own_code(int k) {
  return kFirstOwn - k;
}

}  // namespace

bool AggregationPreconditioner::setup(const SparseRows& matrix, double strength) {
  invert_diagonal(matrix, inverse_diagonal_);
  build_aggregates(matrix, strength);
  build_coarse_matrix(matrix);
  aggregate_of_key_.clear();
  return factorize();
}

bool AggregationPreconditioner::factorize() {
  factor_.compute(coarse_);
  // A pivot at round-off of the largest means a (numerically) singular coarse matrix: the
  // system itself is then only semi-definite, and Jacobi alone is the safe preconditioner.
  factored_ = factor_.info() == Eigen::Success && aggregate_count_ > 0 &&
              factor_.vectorD().minCoeff() > 1e-10 * factor_.vectorD().maxCoeff();
  return factored_;
}

// Aggregation in three passes after Vanek et al. (1996, section 4): (1) greedy in row order, a
// row whose strong neighbours are all free starts an aggregate with them; (2) a row left over
// joins the pass-1 aggregate of its strongest strong neighbour; (3) a row still left starts an
// aggregate of its own. Pass 1 runs on kAggregationStretches equal stretches of the rows, each on
// its own (a neighbour in another stretch is not a candidate); pass 2 reads only pass 1's result,
// across the stretches. So the stretches run side by side and the aggregates do not depend on
// the thread count. The rows are in the particles' cell order: a stretch is a compact piece of
// the domain, and pass 2 mends its border. More stretches cut more aggregates at their borders:
// stretches of 2 048 rows gave 10 % more aggregates and a 20 % denser coarse factor.
void AggregationPreconditioner::build_aggregates(const SparseRows& m, double strength) {
  const int n = m.rows();
  const int stretches = n >= kAggregationSplitRows ? kAggregationStretches : 1;
  const auto first_row = [&](int s) {
    return static_cast<int>(static_cast<std::int64_t>(n) * s / stretches);
  };
  const auto end_row = [&](int s) { return first_row(s + 1); };
  strong_.resize(n);
  aggregate_.assign(n, kNoAggregate);
  joined_.resize(n);
  first_count_.assign(static_cast<std::size_t>(stretches) + 1, 0);
  own_count_.assign(static_cast<std::size_t>(stretches) + 1, 0);
  const bool parallel = n >= 4096;
#pragma omp parallel if (parallel)
  {
#pragma omp for schedule(dynamic)
    for (int s = 0; s < stretches; ++s) {
      first_count_[s + 1] = greedy_pass(m, strength, first_row(s), end_row(s));
    }
#pragma omp single
    {
      for (int s = 0; s < stretches; ++s) first_count_[s + 1] += first_count_[s];
    }
    // Pass 1's numbers to global ones (after the barrier that ends the single).
#pragma omp for schedule(static)
    for (int s = 0; s < stretches; ++s) {
      for (int i = first_row(s); i < end_row(s); ++i) {
        if (aggregate_[i] >= 0) aggregate_[i] += first_count_[s];
      }
    }
#pragma omp for schedule(static)
    for (int s = 0; s < stretches; ++s) {
      own_count_[s + 1] = join_pass(m, first_row(s), end_row(s));
    }
#pragma omp single
    {
      for (int s = 0; s < stretches; ++s) own_count_[s + 1] += own_count_[s];
    }
#pragma omp for schedule(static)
    for (int s = 0; s < stretches; ++s) {
      const int base = first_count_[stretches] + own_count_[s];
      for (int i = first_row(s); i < end_row(s); ++i) {
        aggregate_[i] = joined_[i] >= 0 ? joined_[i] : base + own_code(joined_[i]);
      }
    }
  }
  aggregate_count_ = first_count_[stretches] + own_count_[stretches];
  gather_members(n);
}

// Members of each aggregate in row order (a counting sort); rows without one are left out.
void AggregationPreconditioner::gather_members(int n) {
  const int count = aggregate_count_;
  member_offset_.assign(static_cast<std::size_t>(count) + 1, 0);
  for (int i = 0; i < n; ++i) {
    if (aggregate_[i] >= 0) ++member_offset_[aggregate_[i] + 1];
  }
  for (int a = 0; a < count; ++a) member_offset_[a + 1] += member_offset_[a];
  member_.resize(member_offset_[count]);
  member_cursor_.assign(member_offset_.begin(), member_offset_.end() - 1);
  for (int i = 0; i < n; ++i) {
    if (aggregate_[i] >= 0) member_[member_cursor_[aggregate_[i]]++] = i;
  }
}

void AggregationPreconditioner::export_setup(PressureSetupState& state) const {
  state.aggregate_of_key = aggregate_of_key_;
  state.aggregate_count = aggregate_count_;
  state.coarse_row.clear();
  state.coarse_column.clear();
  state.coarse_value.clear();
  for (int column = 0; column < coarse_.outerSize(); ++column) {
    for (Eigen::SparseMatrix<double>::InnerIterator it(coarse_, column); it; ++it) {
      state.coarse_row.push_back(static_cast<int>(it.row()));
      state.coarse_column.push_back(column);
      state.coarse_value.push_back(it.value());
    }
  }
}

bool AggregationPreconditioner::import_setup(const PressureSetupState& state) {
  aggregate_of_key_ = state.aggregate_of_key;
  aggregate_count_ = state.aggregate_count;
  lower_.clear();
  for (std::size_t k = 0; k < state.coarse_value.size(); ++k) {
    lower_.emplace_back(state.coarse_row[k], state.coarse_column[k], state.coarse_value[k]);
  }
  coarse_.resize(aggregate_count_, aggregate_count_);
  coarse_.setFromTriplets(lower_.begin(), lower_.end());
  return factorize();
}

void AggregationPreconditioner::remember_keys(const std::vector<int>& row_keys, int key_count) {
  aggregate_of_key_.assign(key_count, kNoAggregate);
  for (std::size_t i = 0; i < row_keys.size(); ++i) aggregate_of_key_[row_keys[i]] = aggregate_[i];
}

bool AggregationPreconditioner::reuse(const SparseRows& matrix, const std::vector<int>& row_keys) {
  if (!factored_ || aggregate_of_key_.empty()) return false;
  const int n = matrix.rows();
  invert_diagonal(matrix, inverse_diagonal_);
  aggregate_.resize(n);
  const int keys = static_cast<int>(aggregate_of_key_.size());
  for (int i = 0; i < n; ++i) {
    const int key = row_keys[i];
    aggregate_[i] = key >= 0 && key < keys ? aggregate_of_key_[key] : kNoAggregate;
  }
  gather_members(n);
  return true;
}

// Pass 1 on rows [begin, end), numbering its aggregates from 0; returns their count. Also sets
// the rows' strength thresholds.
int AggregationPreconditioner::greedy_pass(const SparseRows& m, double strength, int begin,
                                           int end) {
  for (int i = begin; i < end; ++i) {
    double largest = 0.0;
    for (std::int64_t k = m.offset[i]; k < m.offset[i + 1]; ++k) {
      if (m.column[k] != i) largest = std::max(largest, -m.value[k]);
    }
    // A row without a negative off-diagonal entry has no strong neighbour.
    strong_[i] = largest > 0.0 ? strength * largest : std::numeric_limits<double>::infinity();
  }
  const auto inside = [&](int j) { return j >= begin && j < end; };
  int count = 0;
  for (int i = begin; i < end; ++i) {
    if (aggregate_[i] >= 0) continue;
    const double strong = strong_[i];
    bool free = true;
    for (std::int64_t k = m.offset[i]; k < m.offset[i + 1]; ++k) {
      const int j = m.column[k];
      if (j != i && inside(j) && -m.value[k] >= strong && aggregate_[j] >= 0) {
        free = false;
        break;
      }
    }
    if (!free) continue;
    aggregate_[i] = count;
    for (std::int64_t k = m.offset[i]; k < m.offset[i + 1]; ++k) {
      const int j = m.column[k];
      if (j != i && inside(j) && -m.value[k] >= strong) aggregate_[j] = count;
    }
    ++count;
  }
  return count;
}

// The label of row i's strongest strong neighbour among those `label` gives one (>= 0 in pass 2,
// <= kFirstOwn in pass 3), or kNoAggregate.
template <class Label>
int strongest_label(const SparseRows& m, const std::vector<double>& strong, int i, Label label) {
  int best = kNoAggregate;
  double best_weight = 0.0;
  for (std::int64_t k = m.offset[i]; k < m.offset[i + 1]; ++k) {
    const int j = m.column[k];
    if (j == i || -m.value[k] < strong[i] || -m.value[k] <= best_weight) continue;
    const int found = label(j);
    if (found == kNoAggregate) continue;
    best_weight = -m.value[k];
    best = found;
  }
  return best;
}

// Passes 2 and 3 on rows [begin, end): joined_ gets each row's global aggregate from pass 1 or 2
// (pass 2 reads pass 1's aggregate_ only), or own_code(k) for the stretch's k-th pass-3 aggregate.
// In pass 3, in row order, a row still left joins the pass-3 aggregate of its strongest strong
// neighbour in the stretch, or starts one. Returns the number of pass-3 aggregates.
int AggregationPreconditioner::join_pass(const SparseRows& m, int begin, int end) {
  for (int i = begin; i < end; ++i) {
    joined_[i] = aggregate_[i] >= 0 ? aggregate_[i] : strongest_label(m, strong_, i, [&](int j) {
      return aggregate_[j] >= 0 ? aggregate_[j] : kNoAggregate;
    });
  }
  int own = 0;
  for (int i = begin; i < end; ++i) {
    if (joined_[i] != kNoAggregate) continue;
    const int best = strongest_label(m, strong_, i, [&](int j) {
      return j >= begin && j < end && joined_[j] <= kFirstOwn ? joined_[j] : kNoAggregate;
    });
    joined_[i] = best != kNoAggregate ? best : own_code(own++);
  }
  return own;
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

double AggregationPreconditioner::apply(const std::vector<double>& r, std::vector<double>& z,
                                        int block, std::vector<double>& partial) {
  const int n = static_cast<int>(r.size());
  z.resize(n);
  const int blocks = (n + block - 1) / block;
  partial.assign(blocks, 0.0);
  if (factored_) {
    // P^T r by aggregate: each sum over the members in row order, as a loop over the rows adds.
    coarse_rhs_.resize(aggregate_count_);
#pragma omp parallel for schedule(static) if (n >= 4096)
    for (int a = 0; a < aggregate_count_; ++a) {
      double sum = 0.0;
      for (int t = member_offset_[a]; t < member_offset_[a + 1]; ++t) sum += r[member_[t]];
      coarse_rhs_[a] = sum;
    }
    coarse_solution_ = factor_.solve(coarse_rhs_);
  }
  // The Jacobi part and the coarse correction in one pass (the same sum, D^-1 r first), and
  // r . z by blocks as dot() sums it, while r and z are in cache.
#pragma omp parallel for schedule(static) if (blocks >= 4)
  for (int b = 0; b < blocks; ++b) {
    const int end = std::min(n, (b + 1) * block);
    double sum = 0.0;
    for (int i = b * block; i < end; ++i) {
      const double jacobi = inverse_diagonal_[i] * r[i];
      z[i] = factored_ && aggregate_[i] >= 0 ? jacobi + coarse_solution_[aggregate_[i]] : jacobi;
      sum += r[i] * z[i];
    }
    partial[b] = sum;
  }
  double total = 0.0;
  for (const double s : partial) total += s;
  return total;
}

}  // namespace cosim::mps
