// Force-included (-include) into MPS-Basic's pressure_poisson_equation.cpp when
// compare_mps_basic.py builds mps_basic_driver, and into nothing else. MPS-Basic solves its
// pressure equation with Eigen::BiCGSTAB at Eigen's default tolerance and reports no iteration
// count. This header swaps in a class derived from Eigen::BiCGSTAB that only
//   - sets the tolerance given to the driver (relative residual |b - A x| / |b|; none given:
//     Eigen's default, machine epsilon, i.e. MPS-Basic as published), and
//   - records iterations() and error() when MPS-Basic calls info() after each solve.
// The solver itself (BiCGSTAB, diagonal preconditioner, zero start) is Eigen's, unchanged.
#pragma once

#include <Eigen/Dense>
#include <Eigen/IterativeLinearSolvers>
#include <Eigen/Sparse>

namespace mps_basic_probe {
double tolerance();  // <= 0: keep Eigen's default
void record(long iterations, double relative_residual);
}  // namespace mps_basic_probe

namespace Eigen {

template <typename MatrixType,
          typename Preconditioner = DiagonalPreconditioner<typename MatrixType::Scalar>>
class ProbedBiCGSTAB : public BiCGSTAB<MatrixType, Preconditioner> {
  using Base = BiCGSTAB<MatrixType, Preconditioner>;

 public:
  ProbedBiCGSTAB() {
    if (mps_basic_probe::tolerance() > 0.0) this->setTolerance(mps_basic_probe::tolerance());
  }
  ComputationInfo info() const {
    mps_basic_probe::record(static_cast<long>(this->iterations()),
                            static_cast<double>(this->error()));
    return Base::info();
  }
};

}  // namespace Eigen

#define BiCGSTAB ProbedBiCGSTAB
