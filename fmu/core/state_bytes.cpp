#include "fmu/core/state_bytes.hpp"

namespace jointcomp::fmu {

namespace {

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

// Magic, format, total size (checked against `size`), checksum, instantiation token and shapes.
void readHeader(StateReader& r, const unsigned char bytes[], std::size_t size, const Model& model) {
  const ModelVariables& table = model.table();
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
      r.get<std::uint32_t>("the header") != model.stateShape()) {
    throw Error("the state has another variable table");
  }
}

void readCore(StateReader& r, const ModelVariables& table, CoreState& s) {
  s.phase = r.get<std::uint32_t>("the phase");
  if (s.phase != kInstantiated && s.phase != kInitializationMode && s.phase != kStepMode && s.phase != kStepDiscarded &&
      s.phase != kTerminated) {
    throw Error("the state's phase is not one a state can be taken in");
  }
  r.vector(s.values, static_cast<std::uint32_t>(table.size()), "the variable values");
  s.time = r.finite("the time");
  s.start_time = r.finite("the start time");
  s.stop_time_defined = r.flag("the stop-time flag");
  s.stop_time = r.finite("the stop time");
  s.initialized = r.flag("the initialised flag");
  if ((s.phase & (kStepMode | kStepDiscarded | kTerminated)) && !s.initialized) {
    throw Error("a state after initialisation without the model's state");
  }
}

// Every parameter and input within its variable's range, of its type.
void checkValues(const ModelVariables& table, const CoreState& s) {
  for (int i = 0; i < table.size(); ++i) {
    const Variable& v = table.variables[static_cast<std::size_t>(i)];
    const double x = s.values[static_cast<std::size_t>(i)];
    if ((v.causality == Causality::Parameter || v.causality == Causality::Input) &&
        (x < v.min || x > v.max || (v.type != VariableType::Real && x != std::floor(x)) ||
         (v.type == VariableType::Boolean && x != 0.0 && x != 1.0))) {
      throw Error("the value of " + describeVariable(table, i) + " is out of its range");
    }
  }
}

}  // namespace

std::vector<unsigned char> serializeState(const Snapshot& state, const Model& model) {
  const ModelVariables& table = model.table();
  const CoreState& s = state.core;
  StateWriter w;
  w.append(kMagic, sizeof kMagic);
  w.put(kStateFormat);
  w.put(std::uint64_t(0));  // total size, patched below
  const std::string& token = table.instantiation_token;
  w.put(static_cast<std::uint32_t>(token.size()));
  w.append(token.data(), token.size());
  w.put(static_cast<std::uint32_t>(table.size()));
  w.put(model.stateShape());
  w.put(static_cast<std::uint32_t>(s.phase));
  w.put(s.values);
  w.put(s.time);
  w.put(s.start_time);
  w.flag(s.stop_time_defined);
  w.put(s.stop_time);
  w.flag(s.initialized);
  model.writeState(s, *state.model, w);
  const std::uint64_t total = w.bytes.size() + sizeof(std::uint64_t);  // with the checksum
  std::memcpy(w.bytes.data() + sizeof kMagic + sizeof kStateFormat, &total, sizeof total);
  w.put(fnv1a(w.bytes.data(), w.bytes.size()));
  return std::move(w.bytes);
}

void deserializeState(const unsigned char bytes[], std::size_t size, const Model& model, Snapshot& into) {
  StateReader r(bytes, size);
  readHeader(r, bytes, size, model);
  CoreState core;
  readCore(r, model.table(), core);
  std::unique_ptr<ModelState> model_state = model.newState();
  model.readState(core, *model_state, r);
  if (r.offset() + sizeof(std::uint64_t) != size) throw Error("the state has bytes after its end");
  checkValues(model.table(), core);
  into.core = std::move(core);
  into.model = std::move(model_state);
}

}  // namespace jointcomp::fmu
