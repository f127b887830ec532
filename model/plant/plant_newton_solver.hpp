// The plant's Newton systems solved by structure: CVODE's linear solver for the flexible-joint plant's
// layout (plant_integrator.cpp hands it to CVODE; FlexibleJointPlant::solveNewtonSystem exposes it to tests).
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>

#include <sundials/sundials_linearsolver.h>

#include "model/common/types.hpp"

namespace jointcomp {

// Solves CVODE's Newton systems (I - gamma J) x = b for the plant's layout y = [q, qd, p, pd, z]: the rows
// of q and p are the identity and -gamma on their own velocity, those of z are diagonal in p, pd and z, so
// q, p and z are eliminated and a 2n x 2n system in (qd, pd) remains, one 12 x 12 LU for the RX170 instead
// of 30 x 30 (the Schur complement further onto 6 would save little more). It reads I - gamma J from the
// Jacobian and gamma (CVODE's linear-system function hands them over) with the arithmetic of SUNDIALS'
// SUNMatScaleAddI, so it never forms the dense 30 x 30 matrix (Debian's SUNDIALS copies and scales it
// unoptimised). Setup checks the layout and fails unrecoverably on a matrix without it.
struct StructuredLinearSolver {
  using Reduced =
      Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::ColMajor, 2 * kMaxJoints, 2 * kMaxJoints>;
  using ReducedVector = Eigen::Matrix<double, Eigen::Dynamic, 1, Eigen::ColMajor, 2 * kMaxJoints, 1>;

  int n = 0;
  Reduced reduced;
  // The rows of qd and pd in I - gamma J, in the columns of q, p and z, read once per setup: every Newton
  // iteration's solve needs them.
  using Coupling = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::ColMajor, 2 * kMaxJoints, kMaxJoints>;
  Coupling by_position, by_motor, by_integral;
  // `reduced` holds its own LU factors after a setup (unit-lower L below the diagonal, U on and above), with
  // the row taken as pivot at each column: a 12x12 by plain loops, a fifth of what Eigen's blocked
  // PartialPivLU of a dynamic matrix costs at this size (it showed in the profile of the FMU's step).
  std::array<int, 2 * kMaxJoints> pivot_row{};
  ReducedVector rhs, solution;
  const double* jacobian = nullptr;  // of the last setup, column-major, 5n x 5n; CVODE keeps it unchanged
  double gamma = 0.0;                // until the next setup
  bool layout_checked = false;       // for this Jacobian (the layout does not depend on gamma)
  // Per joint: q = b_q + position_gain qd, p = b_p + motor_gain pd, and the integral row
  // integral_by_p p + integral_by_pd pd + integral_self z = b_z, so z = (b_z - integral_by_p b_p) / integral_self
  // + integral_by_pd_reduced pd.
  JointVector position_gain, motor_gain, integral_by_p, integral_by_pd, integral_self, integral_by_pd_reduced;
  JointVector integral_offset;
  long last_flag = 0;

  explicit StructuredLinearSolver(int dof)
      : n(dof),
        reduced(2 * dof, 2 * dof),
        by_position(2 * dof, dof),
        by_motor(2 * dof, dof),
        by_integral(2 * dof, dof),
        rhs(2 * dof),
        solution(2 * dof),
        position_gain(dof),
        motor_gain(dof),
        integral_by_p(dof),
        integral_by_pd(dof),
        integral_self(dof),
        integral_by_pd_reduced(dof),
        integral_offset(dof) {}

  // The entry (row, column) of I - gamma J: -gamma J, plus one on the diagonal, as SUNMatScaleAddI forms it.
  double at(int row, int column) const {
    const double scaled = -gamma * jacobian[static_cast<std::size_t>(column) * (5 * n) + row];
    return row == column ? scaled + 1.0 : scaled;
  }

  int setup(const double* jacobian_values, double newton_gamma) {
    jacobian = jacobian_values;
    gamma = newton_gamma;
    const int size = 5 * n;
    for (int k = 0; k < n; ++k) {
      const int q = k, qd = n + k, p = 2 * n + k, pd = 3 * n + k, z = 4 * n + k;
      for (int c = 0; c < size && !layout_checked; ++c) {
        const bool q_row_ok = c == qd || at(q, c) == (c == q ? 1.0 : 0.0);
        const bool p_row_ok = c == pd || at(p, c) == (c == p ? 1.0 : 0.0);
        const bool z_row_ok = c == p || c == pd || c == z || at(z, c) == 0.0;
        if (!q_row_ok || !p_row_ok || !z_row_ok) return last_flag = SUNLS_PACKAGE_FAIL_UNREC;
      }
      position_gain[k] = -at(q, qd);
      motor_gain[k] = -at(p, pd);
      integral_by_p[k] = at(z, p);
      integral_by_pd[k] = at(z, pd);
      integral_self[k] = at(z, z);
      if (integral_self[k] == 0.0) return last_flag = SUNLS_LUFACT_FAIL;
      integral_by_pd_reduced[k] = -(integral_by_p[k] * motor_gain[k] + integral_by_pd[k]) / integral_self[k];
    }
    layout_checked = true;
    for (int i = 0; i < 2 * n; ++i) {
      const int row = i < n ? n + i : 2 * n + i;  // the rows of qd, then those of pd
      for (int k = 0; k < n; ++k) {
        by_position(i, k) = at(row, k);
        by_motor(i, k) = at(row, 2 * n + k);
        by_integral(i, k) = at(row, 4 * n + k);
        reduced(i, k) = at(row, n + k) + by_position(i, k) * position_gain[k];
        reduced(i, n + k) =
            at(row, 3 * n + k) + by_motor(i, k) * motor_gain[k] + by_integral(i, k) * integral_by_pd_reduced[k];
      }
    }
    if (!factorReduced()) return last_flag = SUNLS_LUFACT_FAIL;  // recoverable
    return last_flag = SUNLS_SUCCESS;
  }

  // Gaussian elimination with partial pivoting (the largest magnitude in the column, the first of equals, as
  // LAPACK and Eigen choose) in place; false at a pivot that is zero or not finite.
  bool factorReduced() {
    const int m = 2 * n;
    double* a = reduced.data();  // column-major, m x m: entry (i, j) at a[j * m + i]
    for (int k = 0; k < m; ++k) {
      double* column = a + static_cast<std::ptrdiff_t>(k) * m;
      int pivot = k;
      double largest = std::abs(column[k]);
      for (int i = k + 1; i < m; ++i) {
        const double magnitude = std::abs(column[i]);
        if (magnitude > largest) {
          largest = magnitude;
          pivot = i;
        }
      }
      pivot_row[k] = pivot;
      if (pivot != k) {
        for (int j = 0; j < m; ++j) std::swap(a[j * m + k], a[j * m + pivot]);
      }
      const double diagonal = column[k];
      if (!(diagonal != 0.0) || !std::isfinite(diagonal)) return false;
      for (int i = k + 1; i < m; ++i) column[i] /= diagonal;
      for (int j = k + 1; j < m; ++j) {
        double* target = a + static_cast<std::ptrdiff_t>(j) * m;
        const double above = target[k];
        if (above == 0.0) continue;  // the motor block is mostly zeros; the entries are finite (checked Jacobian)
        for (int i = k + 1; i < m; ++i) target[i] -= column[i] * above;
      }
    }
    return true;
  }

  // solution = reduced^-1 rhs by the factors of the last setup; rhs is overwritten. kJoints: n when known
  // at compile time, 0 otherwise (see solve).
  template <int kJoints>
  void solveReduced() {
    const int m = 2 * (kJoints > 0 ? kJoints : n);
    const double* a = reduced.data();
    double* x = rhs.data();
    for (int k = 0; k < m; ++k) std::swap(x[k], x[pivot_row[k]]);
    for (int k = 0; k < m; ++k) {
      const double value = x[k];
      if (value == 0.0) continue;
      const double* column = a + static_cast<std::ptrdiff_t>(k) * m;
      for (int i = k + 1; i < m; ++i) x[i] -= column[i] * value;
    }
    for (int k = m - 1; k >= 0; --k) {
      const double* column = a + static_cast<std::ptrdiff_t>(k) * m;
      x[k] /= column[k];
      const double value = x[k];
      for (int i = 0; i < k; ++i) x[i] -= column[i] * value;
    }
    solution = rhs;
  }

  // x and b may be the same vector: every value of b is read before x is written where it was.
  int solve(double* x, const double* b) {
    // Six joints, the arms the project models, with the sizes known at compile time: the loops unrolled and
    // paired, a third fewer instructions per Newton iteration; the same operations on each value in the same
    // order, so the same bits as for any other n.
    return n == 6 ? solveWith<6>(x, b) : solveWith<0>(x, b);
  }

  template <int kJoints>
  int solveWith(double* x, const double* b) {
    const int dof = kJoints > 0 ? kJoints : n;
    for (int k = 0; k < dof; ++k)
      integral_offset[k] = (b[4 * dof + k] - integral_by_p[k] * b[2 * dof + k]) / integral_self[k];
    // Column by column (contiguous, so the compiler vectorises it over the rows), each row's sum in the
    // order of k as before: the same bits as row by row.
    for (int i = 0; i < 2 * dof; ++i) rhs[i] = b[i < dof ? dof + i : 2 * dof + i];
    double* value = rhs.data();
    for (int k = 0; k < dof; ++k) {
      const double b_q = b[k], b_p = b[2 * dof + k], b_z = integral_offset[k];
      const double* position = by_position.data() + static_cast<std::ptrdiff_t>(k) * 2 * dof;
      const double* motor = by_motor.data() + static_cast<std::ptrdiff_t>(k) * 2 * dof;
      const double* integral = by_integral.data() + static_cast<std::ptrdiff_t>(k) * 2 * dof;
      for (int i = 0; i < 2 * dof; ++i) value[i] -= position[i] * b_q + motor[i] * b_p + integral[i] * b_z;
    }
    solveReduced<kJoints>();
    for (int k = 0; k < dof; ++k) {
      const double link_rate = solution[k], motor_rate = solution[dof + k];
      x[k] = b[k] + position_gain[k] * link_rate;
      x[dof + k] = link_rate;
      x[2 * dof + k] = b[2 * dof + k] + motor_gain[k] * motor_rate;
      x[3 * dof + k] = motor_rate;
      x[4 * dof + k] = integral_offset[k] + integral_by_pd_reduced[k] * motor_rate;
    }
    return last_flag = SUNLS_SUCCESS;
  }
};

}  // namespace jointcomp
