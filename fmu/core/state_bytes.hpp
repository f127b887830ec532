// An FMU state (fmi2FMUstate, fmi3FMUState) and its bytes: the core's part (phase, values, time) and the
// model's, written and read back with every field checked, in one place. The bytes are: magic, format, total
// size, the instantiation token, the table's size and the model's shape (Model::stateShape), the core's
// fields, the model's, and an FNV-1a checksum of everything before it.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "fmu/core/core_state.hpp"
#include "fmu/core/model.hpp"
#include "model/common/errors.hpp"
#include "model/common/types.hpp"

namespace jointcomp::fmu {

struct Snapshot {
  CoreState core;
  std::unique_ptr<ModelState> model;
};

class StateWriter {
public:
  template <typename T>
  void put(const T& value) {
    append(&value, sizeof(T));
  }
  void append(const void* data, std::size_t size) {
    const std::size_t at = bytes.size();
    bytes.resize(at + size);
    std::memcpy(bytes.data() + at, data, size);
  }
  void put(const JointVector& v) {
    put(static_cast<std::uint32_t>(v.size()));
    for (int i = 0; i < v.size(); ++i) put(v[i]);
  }
  void put(const std::vector<double>& v) {
    put(static_cast<std::uint32_t>(v.size()));
    for (double x : v) put(x);
  }
  void flag(bool b) { put(static_cast<std::uint8_t>(b)); }
  std::vector<unsigned char> bytes;
};

// Reads what StateWriter wrote; throws jointcomp::Error naming the field (`what`) that is short or wrong.
class StateReader {
public:
  StateReader(const unsigned char* data, std::size_t size) : data_(data), size_(size) {}
  template <typename T>
  T get(const char* what) {
    if (size_ - offset_ < sizeof(T)) throw Error(std::string("the state ends inside ") + what);
    T value;
    std::memcpy(&value, data_ + offset_, sizeof(T));
    offset_ += sizeof(T);
    return value;
  }
  double finite(const char* what) {
    const double x = get<double>(what);
    if (!std::isfinite(x)) throw Error(std::string(what) + " is not finite");
    return x;
  }
  bool flag(const char* what) {
    const auto b = get<std::uint8_t>(what);
    if (b > 1) throw Error(std::string(what) + " is not 0 or 1");
    return b == 1;
  }
  template <typename Vector>
  void vector(Vector& v, std::uint32_t expected, const char* what) {
    if (get<std::uint32_t>(what) != expected) throw Error(std::string(what) + " has the wrong size");
    v.resize(expected);
    for (std::uint32_t i = 0; i < expected; ++i) v[i] = finite(what);
  }
  std::size_t offset() const { return offset_; }

private:
  const unsigned char* data_;
  std::size_t size_;
  std::size_t offset_ = 0;
};

std::vector<unsigned char> serializeState(const Snapshot& state, const Model& model);
// Throws jointcomp::Error saying what is wrong: not a jointcomp state, another FMU or format, a wrong size or
// checksum, a value that is not finite or out of its variable's range, bytes after the end.
void deserializeState(const unsigned char bytes[], std::size_t size, const Model& model, Snapshot& into);

}  // namespace jointcomp::fmu
