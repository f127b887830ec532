#include "fmu/instance_state.hpp"

#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>

#include "fmu/variable_binding.hpp"
#include "model/common/errors.hpp"

namespace jointcomp::fmu {

const char* phaseName(unsigned phase) {
  switch (phase) {
    case kInstantiated: return "Instantiated";
    case kInitializationMode: return "InitializationMode";
    case kStepMode: return "StepMode";
    case kStepDiscarded: return "StepDiscarded";
    case kTerminated: return "Terminated";
    case kErrorState: return "Error";
    default: return "?";
  }
}

InstanceState InstanceState::atStart(const VariableTable& table) {
  InstanceState state;
  state.values.reserve(table.variables.size());
  for (const Variable& v : table.variables) state.values.push_back(v.start);
  state.last_q_desired.setZero(table.dof());
  state.earlier_q_desired.setZero(table.dof());
  state.earliest_q_desired.setZero(table.dof());
  OnlineDynamicState& d = state.dynamic;
  for (JointVector* v : {&d.correction, &d.demand_at_start, &d.demand, &d.delta, &d.integral}) v->setZero(table.dof());
  return state;
}

namespace {

// ---- serialisation -----------------------------------------------------------------------------

constexpr char kMagic[8] = {'J', 'C', 'F', 'M', 'U', 'S', 'T', 'A'};
// 2: with the reference source (demo move); 3: the plant's reference blend, the step before the last and
// the dynamic mode's drive filter; 4: the step before those (steps of the inputs are held, not extrapolated)
constexpr std::uint32_t kStateFormat = 4;

std::uint64_t fnv1a(const unsigned char* bytes, std::size_t size) {
  std::uint64_t hash = 1469598103934665603ULL;
  for (std::size_t i = 0; i < size; ++i) {
    hash ^= bytes[i];
    hash *= 1099511628211ULL;
  }
  return hash;
}

class Writer {
public:
  template <typename T>
  void put(const T& value) {
    const auto* p = reinterpret_cast<const unsigned char*>(&value);
    bytes.insert(bytes.end(), p, p + sizeof(T));
  }
  void put(const JointVector& v) {
    put(static_cast<std::uint32_t>(v.size()));
    for (int i = 0; i < v.size(); ++i) put(v[i]);
  }
  void put(const std::vector<double>& v) {
    put(static_cast<std::uint32_t>(v.size()));
    for (double x : v) put(x);
  }
  std::vector<unsigned char> bytes;
};

class Reader {
public:
  Reader(const unsigned char* data, std::size_t size) : data_(data), size_(size) {}
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
  void vector(JointVector& v, std::uint32_t expected, const char* what) {
    if (get<std::uint32_t>(what) != expected) throw Error(std::string(what) + " has the wrong size");
    v.resize(expected);
    for (std::uint32_t i = 0; i < expected; ++i) v[i] = finite(what);
  }
  void vector(std::vector<double>& v, std::uint32_t expected, const char* what) {
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

void writeState(const InstanceState& s, const VariableTable& table, Writer& w) {
  w.bytes.insert(w.bytes.end(), kMagic, kMagic + sizeof kMagic);
  w.put(kStateFormat);
  w.put(std::uint64_t(0));  // total size, patched below
  const std::string& token = table.instantiation_token;
  w.put(static_cast<std::uint32_t>(token.size()));
  w.bytes.insert(w.bytes.end(), token.begin(), token.end());
  w.put(static_cast<std::uint32_t>(table.size()));
  w.put(static_cast<std::uint32_t>(table.dof()));
  w.put(static_cast<std::uint32_t>(s.phase));
  w.put(s.values);
  w.put(s.time);
  w.put(s.start_time);
  w.put(static_cast<std::uint8_t>(s.stop_time_defined));
  w.put(s.stop_time);
  w.put(static_cast<std::uint8_t>(s.initialized));
  if (s.initialized) {
    const PlantState& p = s.plant;
    w.put(p.time);
    w.put(p.y);
    w.put(p.reference);
    w.put(p.reference_velocity);
    w.put(p.reference_acceleration);
    w.put(p.feedforward);
    w.put(p.feedforward_rate);
    w.put(p.reference_time);
    w.put(p.blend_offset);
    w.put(p.blend_offset_velocity);
    w.put(p.blend_offset_acceleration);
    w.put(p.feedforward_offset);
    w.put(p.feedforward_offset_rate);
    w.put(p.blend_duration);
    for (int k = 0; k < 6; ++k) w.put(p.tool_wrench[k]);
    w.put(p.payload_mass);
    for (int k = 0; k < 3; ++k) w.put(p.payload_com[k]);
  }
  w.put(static_cast<std::uint8_t>(s.has_last_step));
  w.put(s.last_q_desired);
  w.put(s.last_step_time);
  w.put(static_cast<std::uint8_t>(s.has_earlier_step));
  w.put(s.earlier_q_desired);
  w.put(s.earlier_step_time);
  w.put(static_cast<std::uint8_t>(s.has_earliest_step));
  w.put(s.earliest_q_desired);
  w.put(s.earliest_step_time);
  w.put(static_cast<std::uint8_t>(s.dynamic.started));
  w.put(s.dynamic.time);
  for (const JointVector* v :
       {&s.dynamic.correction, &s.dynamic.demand_at_start, &s.dynamic.demand, &s.dynamic.delta, &s.dynamic.integral})
    w.put(*v);
  for (int k = 0; k < 6; ++k) w.put(s.applied_wrench[k]);
  w.put(static_cast<std::uint8_t>(s.desired_inputs_set));
  w.put(static_cast<std::uint8_t>(s.demo));
  const std::uint64_t total = w.bytes.size() + sizeof(std::uint64_t);  // with the checksum
  std::memcpy(w.bytes.data() + sizeof kMagic + sizeof kStateFormat, &total, sizeof total);
  w.put(fnv1a(w.bytes.data(), w.bytes.size()));
}

}  // namespace

std::vector<unsigned char> serializeState(const InstanceState& state, const VariableTable& table) {
  Writer writer;
  writeState(state, table, writer);
  return std::move(writer.bytes);
}

InstanceState deserializeState(const unsigned char bytes[], std::size_t size, const VariableTable& table) {
  const auto dof = static_cast<std::uint32_t>(table.dof());
  InstanceState state;
  InstanceState* s = &state;
  Reader r(bytes, size);
  char magic[sizeof kMagic];
  for (char& c : magic) c = r.get<char>("the header");
  if (std::memcmp(magic, kMagic, sizeof kMagic) != 0) throw Error("not a jointcomp FMU state (wrong magic bytes)");
  const auto format = r.get<std::uint32_t>("the header");
  if (format != kStateFormat)
    throw Error("state format " + std::to_string(format) + ", expected " + std::to_string(kStateFormat));
  const auto total = r.get<std::uint64_t>("the header");
  if (total != size)
    throw Error("the state says it has " + std::to_string(total) + " bytes, given " + std::to_string(size));
  std::uint64_t stored_checksum;  // the last 8 bytes; the header read above has more than that
  std::memcpy(&stored_checksum, bytes + size - sizeof stored_checksum, sizeof stored_checksum);
  if (fnv1a(bytes, size - sizeof stored_checksum) != stored_checksum) {
    throw Error("the checksum does not match: the bytes were changed or truncated");
  }
  const auto token_length = r.get<std::uint32_t>("the header");
  if (token_length != table.instantiation_token.size())
    throw Error("the state is from another FMU (instantiation token)");
  std::string token;
  for (std::uint32_t i = 0; i < token_length; ++i) token += r.get<char>("the header");
  if (token != table.instantiation_token)
    throw Error("the state is from another FMU (instantiation token " + token + ")");
  if (r.get<std::uint32_t>("the header") != static_cast<std::uint32_t>(table.size()) ||
      r.get<std::uint32_t>("the header") != dof) {
    throw Error("the state has another variable table");
  }
  s->phase = r.get<std::uint32_t>("the phase");
  if (s->phase != kInstantiated && s->phase != kInitializationMode && s->phase != kStepMode &&
      s->phase != kStepDiscarded && s->phase != kTerminated) {
    throw Error("the state's phase is not one a state can be taken in");
  }
  r.vector(s->values, static_cast<std::uint32_t>(table.size()), "the variable values");
  s->time = r.finite("the time");
  s->start_time = r.finite("the start time");
  s->stop_time_defined = r.flag("the stop-time flag");
  s->stop_time = r.finite("the stop time");
  s->initialized = r.flag("the initialised flag");
  if ((s->phase & (kStepMode | kStepDiscarded | kTerminated)) && !s->initialized) {
    throw Error("a state after initialisation without the plant's state");
  }
  if (s->initialized) {
    PlantState& p = s->plant;
    const std::uint32_t n = dof;
    p.time = r.finite("the plant's time");
    r.vector(p.y, 5 * n, "the plant's state vector");
    r.vector(p.reference, n, "the plant's reference");
    r.vector(p.reference_velocity, n, "the plant's reference velocity");
    r.vector(p.reference_acceleration, n, "the plant's reference acceleration");
    r.vector(p.feedforward, n, "the plant's feed-forward");
    r.vector(p.feedforward_rate, n, "the plant's feed-forward rate");
    p.reference_time = r.finite("the plant's reference time");
    r.vector(p.blend_offset, n, "the plant's reference blend offset");
    r.vector(p.blend_offset_velocity, n, "the plant's reference blend offset velocity");
    r.vector(p.blend_offset_acceleration, n, "the plant's reference blend offset acceleration");
    r.vector(p.feedforward_offset, n, "the plant's feed-forward blend offset");
    r.vector(p.feedforward_offset_rate, n, "the plant's feed-forward blend offset rate");
    p.blend_duration = r.finite("the plant's reference blend duration");
    if (p.blend_duration < 0.0) throw Error("the plant's reference blend duration is negative");
    for (int k = 0; k < 6; ++k) p.tool_wrench[k] = r.finite("the plant's tool wrench");
    p.payload_mass = r.finite("the plant's payload mass");
    for (int k = 0; k < 3; ++k) p.payload_com[k] = r.finite("the plant's payload centre");
  }
  s->has_last_step = r.flag("the last-step flag");
  r.vector(s->last_q_desired, dof, "the last desired positions");
  s->last_step_time = r.finite("the last step time");
  s->has_earlier_step = r.flag("the earlier-step flag");
  r.vector(s->earlier_q_desired, dof, "the earlier desired positions");
  s->earlier_step_time = r.finite("the earlier step time");
  s->has_earliest_step = r.flag("the earliest-step flag");
  r.vector(s->earliest_q_desired, dof, "the earliest desired positions");
  s->earliest_step_time = r.finite("the earliest step time");
  s->dynamic.started = r.flag("the dynamic compensation's start flag");
  s->dynamic.time = r.finite("the dynamic compensation's time");
  r.vector(s->dynamic.correction, dof, "the dynamic compensation's correction");
  r.vector(s->dynamic.demand_at_start, dof, "the dynamic compensation's initial demand");
  r.vector(s->dynamic.demand, dof, "the dynamic compensation's demand");
  r.vector(s->dynamic.delta, dof, "the dynamic compensation's drive offset");
  r.vector(s->dynamic.integral, dof, "the dynamic compensation's drive integral");
  for (int k = 0; k < 6; ++k) s->applied_wrench[k] = r.finite("the applied wrench");
  s->desired_inputs_set = r.flag("the desired-inputs flag");
  s->demo = r.flag("the demo flag");
  if (r.offset() + sizeof(std::uint64_t) != size) throw Error("the state has bytes after its end");
  for (int i = 0; i < table.size(); ++i) {
    const Variable& v = table.variables[static_cast<std::size_t>(i)];
    const double x = s->values[static_cast<std::size_t>(i)];
    if ((v.causality == Causality::Parameter || v.causality == Causality::Input) &&
        (x < v.min || x > v.max || (v.type != VariableType::Real && x != std::floor(x)) ||
         (v.type == VariableType::Boolean && x != 0.0 && x != 1.0))) {
      throw Error("the value of " + describeVariable(table, i) + " is out of its range");
    }
  }
  return state;
}

}  // namespace jointcomp::fmu
