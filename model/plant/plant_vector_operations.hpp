// CVODE's vector operations on the plant's state, compiled with the project.
//
// Debian's SUNDIALS 6.4 is built without optimisation (its N_VLinearSum_Serial spills every value to the
// stack), and CVODE's vector operations were a quarter of the instructions of a plant spiral. These do
// what SUNDIALS' serial vector documents for each operation, case by case with the same arithmetic, so
// that the results are those of N_Vector_Serial bit for bit (tests/plant/test_plant_vector_operations.cpp
// compares them). Of the fused operations only the linear combination is set, with the arithmetic of
// SUNDIALS' generic fallback; for the others CVODE's fallbacks call these.
#pragma once

#include <nvector/nvector_serial.h>

namespace jointcomp {

// Replaces the hot operations of serial vector `vector` (and so of every vector CVODE clones from it).
void useFastVectorOperations(N_Vector vector);

}  // namespace jointcomp
