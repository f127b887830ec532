#include "fmu/description/model_description_xml.hpp"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <set>
#include <utility>
#include <vector>

#include "model/common/errors.hpp"

namespace jointcomp::fmu {
namespace {

// The length of the UTF-8 sequence at text[i] and its code point, or 0 when it is malformed (overlong,
// a surrogate, beyond U+10FFFF, cut short).
std::size_t utf8Sequence(const std::string& text, std::size_t i, char32_t& code) {
  const auto byte = [&](std::size_t k) { return static_cast<unsigned char>(text[k]); };
  const unsigned char first = byte(i);
  std::size_t length = 0;
  char32_t smallest = 0;
  if (first < 0x80) {
    code = first;
    return 1;
  } else if ((first & 0xE0) == 0xC0) {
    length = 2, code = first & 0x1F, smallest = 0x80;
  } else if ((first & 0xF0) == 0xE0) {
    length = 3, code = first & 0x0F, smallest = 0x800;
  } else if ((first & 0xF8) == 0xF0) {
    length = 4, code = first & 0x07, smallest = 0x10000;
  } else {
    return 0;
  }
  if (i + length > text.size()) return 0;
  for (std::size_t k = 1; k < length; ++k) {
    if ((byte(i + k) & 0xC0) != 0x80) return 0;
    code = (code << 6) | (byte(i + k) & 0x3F);
  }
  if (code < smallest || code > 0x10FFFF || (code >= 0xD800 && code <= 0xDFFF)) return 0;
  return length;
}

// Throws naming `what` unless every character of `text` is one XML 1.0 allows, in UTF-8.
void checkXmlText(const std::string& text, const std::string& what) {
  for (std::size_t i = 0; i < text.size();) {
    char32_t code = 0;
    const std::size_t length = utf8Sequence(text, i, code);
    if (length == 0) throw Error(what + ": the text is not UTF-8 (byte " + std::to_string(i) + " of '" + text + "')");
    const bool allowed =
        code >= 0x20 ? code != 0xFFFE && code != 0xFFFF : (code == '\t' || code == '\n' || code == '\r');
    if (!allowed) {
      char name[16];
      std::snprintf(name, sizeof name, "U+%04X", static_cast<unsigned>(code));
      throw Error(what + ": the text holds the character " + name + ", which XML does not allow, at byte " +
                  std::to_string(i));
    }
    i += length;
  }
}

// HTML text (Python's html.escape): &, <, >, " and ' escaped.
std::string htmlText(const std::string& text) {
  std::string out;
  for (const char c : text) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      case '\'': out += "&#x27;"; break;
      default: out += c;
    }
  }
  return out;
}

// name="value" pairs; empty values are left out (FMI's optional attributes), as generate.py did.
using Attributes = std::vector<std::pair<std::string, std::string>>;

std::string attributeList(const Attributes& pairs, const std::string& where) {
  std::string out;
  for (const auto& [name, value] : pairs) {
    if (value.empty()) continue;
    if (!out.empty()) out += ' ';
    out += name + "=" + xmlAttribute(value, where + ", attribute " + name);
  }
  return out;
}

// "<Name a="1" b="2"/>" (or "<Name/>" without attributes).
std::string element(const std::string& name, const Attributes& pairs, const std::string& where) {
  const std::string list = attributeList(pairs, where);
  return "<" + name + (list.empty() ? "" : " " + list) + "/>";
}

std::string where(const VariableTable& table, int index) {
  const Variable& v = table.variables[static_cast<std::size_t>(index)];
  return "modelDescription.xml: variable " + std::to_string(index) + " ('" + v.name + "')";
}

const char* causalityName(Causality causality) {
  switch (causality) {
    case Causality::Parameter: return "parameter";
    case Causality::Input: return "input";
    case Causality::Output: return "output";
    case Causality::Independent: return "independent";
  }
  return "";
}

const char* variabilityName(Variability variability) {
  switch (variability) {
    case Variability::Fixed: return "fixed";
    case Variability::Tunable: return "tunable";
    case Variability::Discrete: return "discrete";
    case Variability::Continuous: return "continuous";
  }
  return "";
}

const char* typeName(VariableType type, int fmi_version) {
  switch (type) {
    case VariableType::Real: return fmi_version == 2 ? "Real" : "Float64";
    case VariableType::Integer: return fmi_version == 2 ? "Integer" : "Int32";
    case VariableType::Boolean: return "Boolean";
    case VariableType::Enumeration: return "Enumeration";
  }
  return "";
}

// A value of the variable as its type writes it: a real's shortest text, true/false, an integer.
std::string valueText(const VariableTable& table, int index, double value, const char* which) {
  const Variable& v = table.variables[static_cast<std::size_t>(index)];
  if (!std::isfinite(value)) throw Error(where(table, index) + ": its " + which + " is not a finite number");
  switch (v.type) {
    case VariableType::Real: return realText(value);
    case VariableType::Boolean: return value != 0.0 ? "true" : "false";
    case VariableType::Integer:
    case VariableType::Enumeration:
      if (value != std::floor(value) || value < -2147483648.0 || value > 2147483647.0)
        throw Error(where(table, index) + ": its " + which + " " + realText(value) + " is not a 32-bit integer");
      return std::to_string(static_cast<long long>(value));
  }
  return "";
}

// The attributes of a variable's type element: declared type, unit, start, min, max. A Boolean has no
// bounds; an enumeration's are written only when declared.
Attributes typeAttributes(const VariableTable& table, int index) {
  const Variable& v = table.variables[static_cast<std::size_t>(index)];
  const bool bounded = v.type != VariableType::Boolean;
  return {{"declaredType", v.type == VariableType::Enumeration ? v.enumeration : ""},
          {"unit", v.type == VariableType::Real ? v.unit : ""},
          {"start", v.has_start ? valueText(table, index, v.start, "start") : ""},
          {"min", bounded && v.has_min ? valueText(table, index, v.min, "min") : ""},
          {"max", bounded && v.has_max ? valueText(table, index, v.max, "max") : ""}};
}

Attributes variableAttributes(const Variable& v) {
  return {{"name", v.name},
          {"valueReference", std::to_string(v.vr)},
          {"description", v.description},
          {"causality", causalityName(v.causality)},
          {"variability", variabilityName(v.variability)}};
}

// Every table-level fact the XML relies on, checked before a line is written: value references equal
// indices, dependencies are inputs of the table and only outputs have them, declared types and units exist.
void checkTable(const VariableTable& table) {
  std::set<std::string> units, enumerations;
  for (const Unit& unit : table.units) units.insert(unit.name);
  for (const EnumerationType& type : table.enumerations) enumerations.insert(type.name);
  for (int i = 0; i < table.size(); ++i) {
    const Variable& v = table.variables[static_cast<std::size_t>(i)];
    if (v.vr != static_cast<std::uint32_t>(i))
      throw Error(where(table, i) + ": its value reference is not its index " + std::to_string(i));
    if (v.type == VariableType::Real && !v.unit.empty() && !units.count(v.unit))
      throw Error(where(table, i) + ": its unit '" + v.unit + "' is not among the table's units");
    if (v.type == VariableType::Enumeration && !enumerations.count(v.enumeration))
      throw Error(where(table, i) + ": its type '" + v.enumeration + "' is not among the table's enumerations");
    if (!v.depends.empty() && v.causality != Causality::Output)
      throw Error(where(table, i) + ": only outputs list the inputs they depend on");
    for (const int k : v.depends) {
      if (k < 0 || k >= table.size() || table.variables[static_cast<std::size_t>(k)].causality != Causality::Input)
        throw Error(where(table, i) + ": it depends on " + std::to_string(k) + ", which is no input of the table");
    }
  }
}

std::string headerAttributes(const VariableTable& table, int fmi_version) {
  const ModelAttributes& m = table.model;
  return attributeList({{"fmiVersion", fmi_version == 2 ? "2.0" : "3.0"},
                        {"modelName", m.model_name},
                        {fmi_version == 2 ? "guid" : "instantiationToken", table.instantiation_token},
                        {"description", m.description},
                        {"author", m.author},
                        {"version", m.version},
                        {"copyright", m.copyright},
                        {"license", m.license},
                        {"generationTool", m.generation_tool},
                        {"variableNamingConvention", "structured"}},
                       "modelDescription.xml: the model's attributes");
}

std::string coSimulation(const VariableTable& table, int fmi_version) {
  const std::string& id = table.model.model_identifier;
  const std::string what = "modelDescription.xml: CoSimulation";
  if (fmi_version == 2) {
    return "  " + element("CoSimulation",
                          {{"modelIdentifier", id},
                           {"canHandleVariableCommunicationStepSize", "true"},
                           {"canInterpolateInputs", "false"},
                           {"maxOutputDerivativeOrder", "0"},
                           {"canRunAsynchronuously", "false"},
                           {"canBeInstantiatedOnlyOncePerProcess", "false"},
                           {"canNotUseMemoryManagementFunctions", "true"},
                           {"canGetAndSetFMUstate", "true"},
                           {"canSerializeFMUstate", "true"},
                           {"providesDirectionalDerivative", "false"}},
                          what);
  }
  return "  " + element("CoSimulation",
                        {{"modelIdentifier", id},
                         {"canBeInstantiatedOnlyOncePerProcess", "false"},
                         {"canGetAndSetFMUState", "true"},
                         {"canSerializeFMUState", "true"},
                         {"providesDirectionalDerivatives", "false"},
                         {"providesAdjointDerivatives", "false"},
                         {"providesPerElementDependencies", "true"},
                         {"canHandleVariableCommunicationStepSize", "true"},
                         {"maxOutputDerivativeOrder", "0"},
                         {"providesIntermediateUpdate", "false"},
                         {"mightReturnEarlyFromDoStep", "false"},
                         {"canReturnEarlyAfterIntermediateUpdate", "false"},
                         {"hasEventMode", "false"}},
                        what);
}

// The units the variables use, in the table's order; nothing when none is used (the schemas want at
// least one Unit in UnitDefinitions).
void unitDefinitions(const VariableTable& table, std::string& out) {
  std::set<std::string> used;
  for (const Variable& v : table.variables) {
    if (v.type == VariableType::Real && !v.unit.empty()) used.insert(v.unit);
  }
  if (used.empty()) return;
  static const char* const kBaseUnits[8] = {"kg", "m", "s", "A", "K", "mol", "cd", "rad"};
  out += "  <UnitDefinitions>\n";
  for (const Unit& unit : table.units) {
    if (!used.count(unit.name)) continue;
    const std::string what = "modelDescription.xml: unit '" + unit.name + "'";
    Attributes exponents;
    for (std::size_t k = 0; k < 8; ++k) {
      if (unit.exponents[k] != 0) exponents.emplace_back(kBaseUnits[k], std::to_string(unit.exponents[k]));
    }
    out += "    <Unit " + attributeList({{"name", unit.name}}, what) + ">\n";
    out += "      " + element("BaseUnit", exponents, what) + "\n";
    out += "    </Unit>\n";
  }
  out += "  </UnitDefinitions>\n";
}

void typeDefinitions(const VariableTable& table, int fmi_version, std::string& out) {
  if (table.enumerations.empty()) return;
  out += "  <TypeDefinitions>\n";
  const std::string indent = fmi_version == 2 ? "      " : "    ";
  for (const EnumerationType& type : table.enumerations) {
    const std::string what = "modelDescription.xml: enumeration '" + type.name + "'";
    if (type.items.empty()) throw Error(what + " has no items");
    const std::string name = attributeList({{"name", type.name}}, what);
    out += fmi_version == 2 ? "    <SimpleType " + name + ">\n      <Enumeration>\n"
                            : "    <EnumerationType " + name + ">\n";
    for (const EnumerationItem& item : type.items) {
      out += indent + "  " +
             element("Item",
                     {{"name", item.name}, {"value", std::to_string(item.value)}, {"description", item.description}},
                     what) +
             "\n";
    }
    out += fmi_version == 2 ? "      </Enumeration>\n    </SimpleType>\n" : "    </EnumerationType>\n";
  }
  out += "  </TypeDefinitions>\n";
}

void logCategoriesAndExperiment(const VariableTable& table, std::string& out) {
  if (!table.log_categories.empty()) {
    out += "  <LogCategories>\n";
    for (const LogCategory& category : table.log_categories) {
      out += "    " +
             element("Category", {{"name", category.name}, {"description", category.description}},
                     "modelDescription.xml: log category '" + category.name + "'") +
             "\n";
    }
    out += "  </LogCategories>\n";
  }
  const ModelAttributes& m = table.model;
  const std::string what = "modelDescription.xml: DefaultExperiment";
  for (const double value : {m.start_time, m.stop_time, m.step_size}) {
    if (!std::isfinite(value)) throw Error(what + ": a time is not a finite number");
  }
  out += "  " +
         element("DefaultExperiment",
                 {{"startTime", realText(m.start_time)},
                  {"stopTime", realText(m.stop_time)},
                  {"stepSize", realText(m.step_size)}},
                 what) +
         "\n";
}

void modelVariables(const VariableTable& table, int fmi_version, std::string& out) {
  out += "  <ModelVariables>\n";
  for (int i = 0; i < table.size(); ++i) {
    const Variable& v = table.variables[static_cast<std::size_t>(i)];
    const std::string what = where(table, i);
    if (fmi_version == 2) {
      out += "    <!-- " + std::to_string(i + 1) + " -->\n";
      out += "    <ScalarVariable " + attributeList(variableAttributes(v), what) + ">\n";
      out += "      " + element(typeName(v.type, 2), typeAttributes(table, i), what) + "\n";
      out += "    </ScalarVariable>\n";
    } else {
      Attributes attributes = variableAttributes(v);
      for (auto& pair : typeAttributes(table, i)) attributes.push_back(std::move(pair));
      out += "    " + element(typeName(v.type, 3), attributes, what) + "\n";
    }
  }
  out += "  </ModelVariables>\n";
}

// The outputs with the inputs each depends on directly, and the outputs as initial unknowns. FMI 2 names
// a variable by its 1-based position in ModelVariables, FMI 3 by its value reference.
void modelStructure(const VariableTable& table, int fmi_version, std::string& out) {
  const int base = fmi_version == 2 ? 1 : 0;
  std::vector<int> outputs;
  for (int i = 0; i < table.size(); ++i) {
    if (table.variables[static_cast<std::size_t>(i)].causality == Causality::Output) outputs.push_back(i);
  }
  const auto dependencies = [&](int i) {
    std::string list;
    for (const int k : table.variables[static_cast<std::size_t>(i)].depends)
      list += (list.empty() ? "" : " ") + std::to_string(k + base);
    return list;
  };
  out += "  <ModelStructure>\n";
  if (fmi_version == 2) {
    if (!outputs.empty()) {
      out += "    <Outputs>\n";
      for (const int i : outputs)
        out += "      <Unknown index=\"" + std::to_string(i + 1) + "\" dependencies=\"" + dependencies(i) + "\"/>\n";
      out += "    </Outputs>\n    <InitialUnknowns>\n";
      for (const int i : outputs) out += "      <Unknown index=\"" + std::to_string(i + 1) + "\"/>\n";
      out += "    </InitialUnknowns>\n";
    }
  } else {
    for (const int i : outputs)
      out += "    <Output valueReference=\"" + std::to_string(i) + "\" dependencies=\"" + dependencies(i) + "\"/>\n";
    for (const int i : outputs) out += "    <InitialUnknown valueReference=\"" + std::to_string(i) + "\"/>\n";
  }
  out += "  </ModelStructure>\n";
}

}  // namespace

std::string realText(double value) {
  if (!std::isfinite(value)) throw Error("a number in modelDescription.xml is not finite");
  char buffer[64];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, value, std::chars_format::scientific);
  const std::string text(buffer, result.ptr);  // shortest round trip: "-1.25e+02"
  const std::size_t e = text.find('e');
  const bool negative = text[0] == '-';
  std::string digits;
  for (std::size_t k = negative ? 1 : 0; k < e; ++k) {
    if (text[k] != '.') digits += text[k];
  }
  const int exponent = std::atoi(text.c_str() + e + 1);
  const int point = exponent + 1;  // digits are 0.d1d2... times 10^point
  const int count = static_cast<int>(digits.size());
  std::string out = negative ? "-" : "";
  if (point <= -4 || point > 16) {  // Python's repr switches to the exponent form there
    out += digits.substr(0, 1) + (count > 1 ? "." + digits.substr(1) : "");
    const int magnitude = std::abs(exponent);
    out += std::string(exponent < 0 ? "e-" : "e+") + (magnitude < 10 ? "0" : "") + std::to_string(magnitude);
  } else if (point <= 0) {
    out += "0." + std::string(static_cast<std::size_t>(-point), '0') + digits;
  } else if (point < count) {
    out += digits.substr(0, static_cast<std::size_t>(point)) + "." + digits.substr(static_cast<std::size_t>(point));
  } else {
    out += digits + std::string(static_cast<std::size_t>(point - count), '0') + ".0";
  }
  return out;
}

std::string xmlAttribute(const std::string& text, const std::string& what) {
  checkXmlText(text, what);
  std::string escaped;
  for (const char c : text) {
    switch (c) {
      case '&': escaped += "&amp;"; break;
      case '<': escaped += "&lt;"; break;
      case '>': escaped += "&gt;"; break;
      case '\n': escaped += "&#10;"; break;
      case '\r': escaped += "&#13;"; break;
      case '\t': escaped += "&#9;"; break;
      default: escaped += c;
    }
  }
  if (escaped.find('"') == std::string::npos) return "\"" + escaped + "\"";
  if (escaped.find('\'') == std::string::npos) return "'" + escaped + "'";
  std::string quoted = "\"";
  for (const char c : escaped) quoted += c == '"' ? std::string("&quot;") : std::string(1, c);
  return quoted + "\"";
}

std::string modelDescriptionXml(const VariableTable& table, int fmi_version) {
  if (fmi_version != 2 && fmi_version != 3)
    throw Error("modelDescription.xml: FMI version " + std::to_string(fmi_version) + " is neither 2 nor 3");
  checkTable(table);
  std::string out = "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<fmiModelDescription " +
                    headerAttributes(table, fmi_version) + (fmi_version == 2 ? " numberOfEventIndicators=\"0\"" : "") +
                    ">\n";
  out += coSimulation(table, fmi_version) + "\n";
  unitDefinitions(table, out);
  typeDefinitions(table, fmi_version, out);
  logCategoriesAndExperiment(table, out);
  modelVariables(table, fmi_version, out);
  modelStructure(table, fmi_version, out);
  out += "</fmiModelDescription>\n";
  return out;
}

std::string variablesHtml(const VariableTable& table) {
  checkTable(table);
  const std::string title = htmlText(table.model.model_name);
  std::string items;
  for (const EnumerationType& type : table.enumerations) {
    items += "<li>" + htmlText(type.name) + ": ";
    for (std::size_t k = 0; k < type.items.size(); ++k) {
      const EnumerationItem& item = type.items[k];
      items += (k ? ", " : "") + htmlText(item.name) + " = " + std::to_string(item.value) + " (" +
               htmlText(item.description) + ")";
    }
    items += "</li>";
  }
  std::string rows;
  for (int i = 0; i < table.size(); ++i) {
    const Variable& v = table.variables[static_cast<std::size_t>(i)];
    const std::string type =
        std::string(typeName(v.type, 2)) + (v.type == VariableType::Enumeration ? " (" + v.enumeration + ")" : "");
    const std::string start = v.has_start ? valueText(table, i, v.start, "start") : "";
    rows += "<tr>";
    for (const std::string& cell : {std::to_string(v.vr), v.name, std::string(causalityName(v.causality)),
                                    std::string(variabilityName(v.variability)), type, v.unit, start, v.description})
      rows += "<td>" + htmlText(cell) + "</td>";
    rows += "</tr>\n";
  }
  return "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>" + title +
         " variables</title></head><body>\n<h1>" + title + " " + htmlText(table.model.version) +
         ": variables</h1>\n<p>The variables of the FMU of the robot " + htmlText(table.robot_name) +
         ", written by jointcomp export-fmu from its URDF and parameter file.</p>\n<ul>" + items +
         "</ul>\n<table border=\"1\"><tr><th>vr</th><th>name</th><th>causality</th><th>variability</th>"
         "<th>type</th><th>unit</th><th>start</th><th>description</th></tr>\n" +
         rows + "</table></body></html>\n";
}

}  // namespace jointcomp::fmu
