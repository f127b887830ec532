// Typed exceptions of the model layers. Messages name the file, element, field or argument at fault;
// the C API and the FMU turn them into status codes at their boundary.
#pragma once

#include <stdexcept>
#include <string>

namespace jointcomp {

// Base of every error jointcomp raises on purpose.
class Error : public std::runtime_error {
public:
  using std::runtime_error::runtime_error;
};

// A robot description (URDF) that is malformed or describes what the model cannot represent.
class UrdfError : public Error {
public:
  using Error::Error;
};

// A joint-error parameter file (JSON) that is malformed, incomplete or out of range.
class ParameterError : public Error {
public:
  using Error::Error;
};

// A measurement campaign file that does not follow formats/measurements.md.
class MeasurementError : public Error {
public:
  using Error::Error;
};

// An argument of a call that is wrong: size mismatch, NaN or infinity, out of range.
class InvalidArgument : public Error {
public:
  using Error::Error;
};

// A Cartesian target the robot cannot reach (outside the workspace or beyond the joint limits).
class UnreachableError : public Error {
public:
  using Error::Error;
};

// A numerical solver that failed: no convergence, singular system, integrator failure.
class SolverError : public Error {
public:
  using Error::Error;
};

// A simulation that left what it may do: a link beyond its joint limits, a drive beyond its tracking
// envelope (following error). The integration itself succeeded; the run is not worth continuing.
class PlantLimitError : public Error {
public:
  using Error::Error;
};

}  // namespace jointcomp
