#include "model/plant/plant_vector_operations.hpp"

#include <cmath>

namespace jointcomp {
namespace {

inline double* data(N_Vector v) { return NV_DATA_S(v); }
inline sunindextype length(N_Vector v) { return NV_LENGTH_S(v); }

// z = a x + b y, with SUNDIALS' special cases: each computes its sum in its own way (c (x + y) for a = b,
// y + a x in place, ...), and the same way here.
void linearSum(realtype a, N_Vector x, realtype b, N_Vector y, N_Vector z) {
  const sunindextype n = length(x);
  const double* xd = data(x);
  const double* yd = data(y);
  double* zd = data(z);
  if (b == 1.0 && z == y) {  // y += a x
    if (a == 1.0) {
      for (sunindextype i = 0; i < n; ++i) zd[i] += xd[i];
    } else if (a == -1.0) {
      for (sunindextype i = 0; i < n; ++i) zd[i] -= xd[i];
    } else {
      for (sunindextype i = 0; i < n; ++i) zd[i] += a * xd[i];
    }
    return;
  }
  if (a == 1.0 && z == x) {  // x += b y
    if (b == 1.0) {
      for (sunindextype i = 0; i < n; ++i) zd[i] += yd[i];
    } else if (b == -1.0) {
      for (sunindextype i = 0; i < n; ++i) zd[i] -= yd[i];
    } else {
      for (sunindextype i = 0; i < n; ++i) zd[i] += b * yd[i];
    }
    return;
  }
  if (a == 1.0 && b == 1.0) {
    for (sunindextype i = 0; i < n; ++i) zd[i] = xd[i] + yd[i];
  } else if (a == 1.0 && b == -1.0) {
    for (sunindextype i = 0; i < n; ++i) zd[i] = xd[i] - yd[i];
  } else if (a == -1.0 && b == 1.0) {
    for (sunindextype i = 0; i < n; ++i) zd[i] = yd[i] - xd[i];
  } else if (a == 1.0) {
    for (sunindextype i = 0; i < n; ++i) zd[i] = b * yd[i] + xd[i];
  } else if (b == 1.0) {
    for (sunindextype i = 0; i < n; ++i) zd[i] = a * xd[i] + yd[i];
  } else if (a == -1.0) {
    for (sunindextype i = 0; i < n; ++i) zd[i] = b * yd[i] - xd[i];
  } else if (b == -1.0) {
    for (sunindextype i = 0; i < n; ++i) zd[i] = a * xd[i] - yd[i];
  } else if (a == b) {
    for (sunindextype i = 0; i < n; ++i) zd[i] = a * (xd[i] + yd[i]);
  } else if (a == -b) {
    for (sunindextype i = 0; i < n; ++i) zd[i] = a * (xd[i] - yd[i]);
  } else {
    for (sunindextype i = 0; i < n; ++i) zd[i] = a * xd[i] + b * yd[i];
  }
}

// z = c x (a copy for c = 1 and a negation for c = -1 give the same values).
void scale(realtype c, N_Vector x, N_Vector z) {
  const sunindextype n = length(x);
  const double* xd = data(x);
  double* zd = data(z);
  for (sunindextype i = 0; i < n; ++i) zd[i] = c * xd[i];
}

void constant(realtype c, N_Vector z) {
  const sunindextype n = length(z);
  double* zd = data(z);
  for (sunindextype i = 0; i < n; ++i) zd[i] = c;
}

void absolute(N_Vector x, N_Vector z) {
  const sunindextype n = length(x);
  const double* xd = data(x);
  double* zd = data(z);
  for (sunindextype i = 0; i < n; ++i) zd[i] = std::fabs(xd[i]);
}

void inverse(N_Vector x, N_Vector z) {
  const sunindextype n = length(x);
  const double* xd = data(x);
  double* zd = data(z);
  for (sunindextype i = 0; i < n; ++i) zd[i] = 1.0 / xd[i];
}

realtype minimum(N_Vector x) {
  const sunindextype n = length(x);
  const double* xd = data(x);
  double smallest = xd[0];
  for (sunindextype i = 1; i < n; ++i) {
    if (xd[i] < smallest) smallest = xd[i];
  }
  return smallest;
}

// sqrt(sum (x_i w_i)^2 / n), summed in order.
realtype weightedRmsNorm(N_Vector x, N_Vector w) {
  const sunindextype n = length(x);
  const double* xd = data(x);
  const double* wd = data(w);
  double sum = 0.0;
  for (sunindextype i = 0; i < n; ++i) {
    const double product = xd[i] * wd[i];
    sum += product * product;
  }
  const double mean = sum / static_cast<double>(n);
  return mean <= 0.0 ? 0.0 : std::sqrt(mean);
}

}  // namespace

void useFastVectorOperations(N_Vector vector) {
  vector->ops->nvlinearsum = linearSum;
  vector->ops->nvscale = scale;
  vector->ops->nvconst = constant;
  vector->ops->nvabs = absolute;
  vector->ops->nvinv = inverse;
  vector->ops->nvmin = minimum;
  vector->ops->nvwrmsnorm = weightedRmsNorm;
}

}  // namespace jointcomp
