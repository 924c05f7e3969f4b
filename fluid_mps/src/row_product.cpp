#include "row_product.hpp"

#include <algorithm>
#include <type_traits>
#ifdef __SSE2__
#include <emmintrin.h>
#endif

namespace cosim::mps {
namespace {

// The rows' own layout, double values and int columns (the true residuals of a float product
// read the matrix so). Past the shortest row of a group a row that has ended keeps its sum (a
// select: no term is added that the plain loop would not add).
void multiply_own_rows(const SparseRows& m, const double* x, int begin, int end, double* y) {
  const std::int64_t* offset = m.offset.data();
  const int* column = m.column.data();
  const double* value = m.value.data();
  const std::int64_t entries = offset[m.rows()];
  int i = begin;
  for (; i + kRowGroup <= end; i += kRowGroup) {
    std::int64_t first[kRowGroup], length[kRowGroup];
    double sum[kRowGroup];
    std::int64_t shortest = offset[i + 1] - offset[i], longest = 0;
    for (int g = 0; g < kRowGroup; ++g) {
      first[g] = offset[i + g];
      length[g] = offset[i + g + 1] - first[g];
      shortest = std::min(shortest, length[g]);
      longest = std::max(longest, length[g]);
      sum[g] = 0.0;
    }
    for (std::int64_t t = 0; t < shortest; ++t) {
      for (int g = 0; g < kRowGroup; ++g) {
        sum[g] += value[first[g] + t] * x[column[first[g] + t]];
      }
    }
    if (first[kRowGroup - 1] + longest <= entries) {
      // The slots past a row's end are those of the next rows: valid to read, never summed.
      for (std::int64_t t = shortest; t < longest; ++t) {
        for (int g = 0; g < kRowGroup; ++g) {
          const double added = sum[g] + value[first[g] + t] * x[column[first[g] + t]];
          sum[g] = t < length[g] ? added : sum[g];
        }
      }
    } else {
      for (int g = 0; g < kRowGroup; ++g) {
        for (std::int64_t k = first[g] + shortest; k < first[g] + length[g]; ++k) {
          sum[g] += value[k] * x[column[k]];
        }
      }
    }
    for (int g = 0; g < kRowGroup; ++g) y[i + g] = sum[g];
  }
  for (; i < end; ++i) {
    double sum = 0.0;
    for (std::int64_t k = offset[i]; k < offset[i + 1]; ++k) {
      sum += value[k] * x[column[k]];
    }
    y[i] = sum;
  }
}

// The interleaved groups. A padding slot holds a zero value (and the group's first row as its
// column): it adds +0 or -0 to its row's sum, which leaves the sum as it is (the sum starts at
// +0, so it is never -0). With SSE2 two rows' slots are multiplied and added in one instruction
// each, lane by lane as the scalar operations round: the same bits.
template <class Column, class Value>
void multiply_groups(const std::int64_t* group_start, const Value* group_value,
                     const Column* group_column, const double* x, int begin, int end, double* y) {
  static_assert(kRowGroup % 2 == 0);
  for (int g = begin / kRowGroup; g * kRowGroup < end; ++g) {
    const std::int64_t start = group_start[g];
    const std::int64_t width = (group_start[g + 1] - start) / kRowGroup;
    const Value* value = group_value + start;
    const Column* column = group_column + start;
    double sum[kRowGroup];
#ifdef __SSE2__
    __m128d pair_sum[kRowGroup / 2];
    for (int h = 0; h < kRowGroup / 2; ++h) pair_sum[h] = _mm_setzero_pd();
    for (std::int64_t t = 0; t < width; ++t) {
      const Value* v = value + kRowGroup * t;
      const Column* c = column + kRowGroup * t;
      __m128d values[kRowGroup / 2];
      if constexpr (std::is_same_v<Value, float>) {
        static_assert(kRowGroup == 4);
        const __m128 four = _mm_loadu_ps(v);
        values[0] = _mm_cvtps_pd(four);
        values[1] = _mm_cvtps_pd(_mm_movehl_ps(four, four));
      } else {
        for (int h = 0; h < kRowGroup / 2; ++h) values[h] = _mm_loadu_pd(v + 2 * h);
      }
      for (int h = 0; h < kRowGroup / 2; ++h) {
        const __m128d xs = _mm_loadh_pd(_mm_load_sd(x + c[2 * h]), x + c[2 * h + 1]);
        pair_sum[h] = _mm_add_pd(pair_sum[h], _mm_mul_pd(values[h], xs));
      }
    }
    for (int h = 0; h < kRowGroup / 2; ++h) _mm_storeu_pd(sum + 2 * h, pair_sum[h]);
#else
    for (int r = 0; r < kRowGroup; ++r) sum[r] = 0.0;
    for (std::int64_t t = 0; t < width; ++t) {
      for (int r = 0; r < kRowGroup; ++r) {
        sum[r] += static_cast<double>(value[kRowGroup * t + r]) * x[column[kRowGroup * t + r]];
      }
    }
#endif
    const int first = g * kRowGroup;
    for (int r = 0; r < kRowGroup && first + r < end; ++r) y[first + r] = sum[r];
  }
}

template <class Column, class Value>
void interleave(const SparseRows& m, const std::vector<std::int64_t>& start,
                std::vector<Value>& group_value, std::vector<Column>& group_column) {
  const int n = m.rows();
  const int groups = static_cast<int>(start.size()) - 1;
  group_value.resize(start[groups]);
  group_column.resize(start[groups]);
#pragma omp parallel for schedule(static) if (groups >= 1024)
  for (int g = 0; g < groups; ++g) {
    const std::int64_t width = (start[g + 1] - start[g]) / kRowGroup;
    Value* value = group_value.data() + start[g];
    Column* column = group_column.data() + start[g];
    for (int r = 0; r < kRowGroup; ++r) {
      const int i = g * kRowGroup + r;
      const std::int64_t first = i < n ? m.offset[i] : 0;
      const std::int64_t length = i < n ? m.offset[i + 1] - first : 0;
      for (std::int64_t t = 0; t < width; ++t) {
        const bool entry = t < length;
        value[kRowGroup * t + r] = static_cast<Value>(entry ? m.value[first + t] : 0.0);
        column[kRowGroup * t + r] =
            static_cast<Column>(entry ? m.column[first + t] : g * kRowGroup);
      }
    }
  }
}

}  // namespace

RowView row_view(const SparseRows& m, CgWork& work, bool single) {
  RowView view;
  view.m = &m;
  const int n = m.rows();
  const int groups = (n + kRowGroup - 1) / kRowGroup;
  std::vector<std::int64_t>& start = work.group_start;
  start.resize(static_cast<std::size_t>(groups) + 1);
  start[0] = 0;
  for (int g = 0; g < groups; ++g) {
    std::int64_t width = 0;
    for (int i = g * kRowGroup; i < std::min(n, (g + 1) * kRowGroup); ++i) {
      width = std::max(width, m.offset[i + 1] - m.offset[i]);
    }
    start[g + 1] = start[g] + kRowGroup * width;
  }
  view.group_start = start.data();
  const auto values = [&](auto& column) {
    if (single) {
      interleave(m, start, work.group_single_value, column);
      view.group_single_value = work.group_single_value.data();
    } else {
      interleave(m, start, work.group_value, column);
      view.group_value = work.group_value.data();
    }
  };
  if (n <= 65536) {
    values(work.group_short_column);
    view.group_short_column = work.group_short_column.data();
  } else {
    values(work.group_column);
    view.group_column = work.group_column.data();
  }
  return view;
}

RowView exact_view(const RowView& view) {
  if (!view.group_single_value) return view;
  RowView exact;  // the double values in the rows' own layout
  exact.m = view.m;
  return exact;
}

void multiply_rows(const RowView& view, const double* x, int begin, int end, double* y) {
  const auto groups = [&](const auto* value) {
    if (view.group_short_column) {
      multiply_groups(view.group_start, value, view.group_short_column, x, begin, end, y);
    } else {
      multiply_groups(view.group_start, value, view.group_column, x, begin, end, y);
    }
  };
  if (view.group_single_value) {
    groups(view.group_single_value);
  } else if (view.group_value) {
    groups(view.group_value);
  } else {
    multiply_own_rows(*view.m, x, begin, end, y);
  }
}

}  // namespace cosim::mps
