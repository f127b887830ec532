// The plant's CVODE vector operations (model/plant/plant_vector_operations.*) against SUNDIALS' serial
// vector: every case of N_VLinearSum (a and b of 1, -1, equal, opposite, other; in place into x or y),
// scale, constant, abs, inverse, min and the weighted RMS norm must give the same doubles, bit for bit, so
// that the plant's runs (and its stored regressions) do not move.
#include <cmath>
#include <cstring>
#include <random>
#include <vector>

#include <gtest/gtest.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>

#include "model/plant/plant_vector_operations.hpp"

namespace jointcomp {
namespace {

constexpr sunindextype kLength = 30;

// count serial vectors (at least 3: x, y and z are the first three) and their context, freed on every way
// out of a test, an ASSERT's early return included.
struct Vectors {
  explicit Vectors(int count = 3) {
    SUNContext_Create(nullptr, &context);
    for (int k = 0; k < count; ++k) all.push_back(N_VNew_Serial(kLength, context));
    x = all[0];
    y = all[1];
    z = all[2];
  }
  ~Vectors() {
    for (N_Vector v : all) N_VDestroy(v);
    SUNContext_Free(&context);
  }
  Vectors(const Vectors&) = delete;
  Vectors& operator=(const Vectors&) = delete;
  SUNContext context = nullptr;
  std::vector<N_Vector> all;
  N_Vector x = nullptr, y = nullptr, z = nullptr;
};

void fill(N_Vector v, std::mt19937_64& random) {
  std::uniform_real_distribution<double> value(-3.0, 3.0);
  for (sunindextype i = 0; i < kLength; ++i) NV_Ith_S(v, i) = value(random) * std::pow(10.0, value(random));
}

bool sameBits(N_Vector a, N_Vector b) { return std::memcmp(NV_DATA_S(a), NV_DATA_S(b), sizeof(double) * kLength) == 0; }

TEST(PlantVectorOperations, EqualSundialsSerialBitForBit) {
  Vectors serial, fast;
  for (N_Vector v : {fast.x, fast.y, fast.z}) useFastVectorOperations(v);
  ASSERT_NE(fast.x->ops->nvlinearsum, serial.x->ops->nvlinearsum);  // the operations were replaced
  std::mt19937_64 random(17);
  const double coefficients[] = {1.0, -1.0, 0.0, 0.37, -2.5, 2.5, -0.37};
  int cases = 0;
  for (double a : coefficients) {
    for (double b : coefficients) {
      for (int target = 0; target < 3; ++target) {  // into z, in place into x, in place into y
        fill(serial.x, random);
        fill(serial.y, random);
        fill(serial.z, random);
        N_VScale_Serial(1.0, serial.x, fast.x);
        N_VScale_Serial(1.0, serial.y, fast.y);
        N_VScale_Serial(1.0, serial.z, fast.z);
        N_Vector serial_out = target == 0 ? serial.z : target == 1 ? serial.x : serial.y;
        N_Vector fast_out = target == 0 ? fast.z : target == 1 ? fast.x : fast.y;
        N_VLinearSum_Serial(a, serial.x, b, serial.y, serial_out);
        N_VLinearSum(a, fast.x, b, fast.y, fast_out);
        EXPECT_TRUE(sameBits(serial_out, fast_out)) << "a = " << a << ", b = " << b << ", target " << target;
        ++cases;
      }
    }
  }
  EXPECT_EQ(cases, 147);
  for (double c : coefficients) {
    fill(serial.x, random);
    N_VScale_Serial(1.0, serial.x, fast.x);
    N_VScale_Serial(c, serial.x, serial.z);
    N_VScale(c, fast.x, fast.z);
    EXPECT_TRUE(sameBits(serial.z, fast.z)) << "scale by " << c;
    N_VScale_Serial(c, serial.x, serial.x);  // in place
    N_VScale(c, fast.x, fast.x);
    EXPECT_TRUE(sameBits(serial.x, fast.x)) << "scale in place by " << c;
    N_VConst_Serial(c, serial.z);
    N_VConst(c, fast.z);
    EXPECT_TRUE(sameBits(serial.z, fast.z)) << "constant " << c;
  }
  fill(serial.x, random);
  fill(serial.y, random);
  N_VScale_Serial(1.0, serial.x, fast.x);
  N_VScale_Serial(1.0, serial.y, fast.y);
  N_VAbs_Serial(serial.x, serial.z);
  N_VAbs(fast.x, fast.z);
  EXPECT_TRUE(sameBits(serial.z, fast.z)) << "abs";
  N_VInv_Serial(serial.x, serial.z);
  N_VInv(fast.x, fast.z);
  EXPECT_TRUE(sameBits(serial.z, fast.z)) << "inverse";
  EXPECT_EQ(N_VMin_Serial(serial.x), N_VMin(fast.x));
  const double serial_norm = N_VWrmsNorm_Serial(serial.x, serial.y);
  const double fast_norm = N_VWrmsNorm(fast.x, fast.y);
  EXPECT_EQ(std::memcmp(&serial_norm, &fast_norm, sizeof(double)), 0) << serial_norm << " vs " << fast_norm;
  N_VConst_Serial(0.0, serial.x);
  N_VConst(0.0, fast.x);
  EXPECT_EQ(N_VWrmsNorm_Serial(serial.x, serial.y), N_VWrmsNorm(fast.x, fast.y));
}

// The fused linear combination against SUNDIALS' generic one (N_VLinearCombination on serial vectors without
// fused operations: a scale and nvec - 1 linear sums), for 1 to 6 vectors, coefficients of 1, -1, 0 and
// others, into a fourth vector and in place into the first or the third (read as summed so far).
TEST(PlantVectorOperations, LinearCombinationEqualsSundialsGenericOneBitForBit) {
  Vectors generic_vectors(7), fast_vectors(7);
  std::vector<N_Vector>& generic = generic_vectors.all;
  std::vector<N_Vector>& fast = fast_vectors.all;
  for (N_Vector v : fast) useFastVectorOperations(v);
  ASSERT_EQ(generic[0]->ops->nvlinearcombination, nullptr);  // Debian's serial vectors: the generic sum
  ASSERT_NE(fast[0]->ops->nvlinearcombination, nullptr);
  std::mt19937_64 random(23);
  const double coefficients[] = {1.0, -1.0, 0.0, 0.37, -2.5, 2.5, 1e-3};
  std::uniform_int_distribution<int> pick(0, 6);
  int cases = 0;
  for (int nvec = 1; nvec <= 6; ++nvec) {
    for (int target = 0; target < 3; ++target) {  // into another vector, in place into X[0], into X[2]
      if (target == 2 && nvec < 3) continue;
      for (int draw = 0; draw < 20; ++draw) {
        std::vector<double> c;
        for (int k = 0; k < 7; ++k) {
          fill(generic[k], random);
          N_VScale_Serial(1.0, generic[k], fast[k]);
        }
        for (int k = 0; k < nvec; ++k) c.push_back(coefficients[pick(random)]);
        const int out = target == 0 ? 6 : target == 1 ? 0 : 2;
        ASSERT_EQ(N_VLinearCombination(nvec, c.data(), generic.data(), generic[out]), 0);
        ASSERT_EQ(N_VLinearCombination(nvec, c.data(), fast.data(), fast[out]), 0);
        EXPECT_TRUE(sameBits(generic[out], fast[out])) << nvec << " vectors, target " << target;
        ++cases;
      }
    }
  }
  EXPECT_EQ(cases, 320);
}

}  // namespace
}  // namespace jointcomp
