// modelDescription.xml from a hand-made two-joint variable table, read back by independent readers:
// xmllint against the FMI schemas (JOINTCOMP_SHARED/fmi-schema) and Python's ElementTree, which reports
// the units, the variables with their attributes and the ModelStructure by name, so that the 1-based
// positions of FMI 2 and the value references of FMI 3 are both checked against the table.
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <set>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "fmu/description/model_description_xml.hpp"
#include "model/common/errors.hpp"
#include "tests/support/child_process.hpp"
#include "tests/support/shared_data.hpp"

namespace jointcomp::fmu {
namespace {

constexpr const char* kPython = "/usr/bin/python3";

// The double a text reads as (std::stod refuses subnormal numbers such as 5e-324).
double readDouble(const std::string& text) { return std::strtod(text.c_str(), nullptr); }

Variable variable(const std::string& name, VariableType type, Causality causality, Variability variability,
                  const std::string& unit = "") {
  Variable v;
  v.name = name, v.type = type, v.causality = causality, v.variability = variability, v.unit = unit;
  return v;
}

Variable startingAt(Variable v, double start) {
  v.has_start = true;
  v.start = start;
  return v;
}

// A robot of two joints, "joint_a" and "joint b" (a name structured naming must quote), with a parameter
// of every type, inputs, and outputs of which some depend on inputs and some on none.
VariableTable twoJointTable() {
  VariableTable t;
  t.model.version = "1.2.3";
  t.model.description = "two joints <test> & \"quotes\" 'too'";
  t.robot_name = "two";
  t.joint_names = {"joint_a", "joint b"};
  t.instantiation_token = "{01234567-89ab-cdef-0123-456789abcdef}";
  t.units = {{"s", {0, 0, 1, 0, 0, 0, 0, 0}, "second"},
             {"m", {0, 1, 0, 0, 0, 0, 0, 0}, "metre (no variable uses it)"},
             {"rad", {0, 0, 0, 0, 0, 0, 0, 1}, "radian"},
             {"rad/s2", {0, 0, -2, 0, 0, 0, 0, 1}, "radian per second squared"},
             {"N.m/(rad.s)", {1, 2, -3, 0, 0, 0, 0, -1}, "integral gain"}};
  t.enumerations = {{"CompensationMode", {{"none", 0, "off"}, {"stiffness", 1, ""}, {"dynamic", 3, "a < b"}}}};
  t.log_categories = {{"logStatusError", "Errors"}, {"logCalls", "Every call"}};
  auto& v = t.variables;
  v.push_back(variable("time", VariableType::Real, Causality::Independent, Variability::Continuous, "s"));
  Variable mode =
      startingAt(variable("compensation", VariableType::Enumeration, Causality::Parameter, Variability::Tunable), 3);
  mode.enumeration = "CompensationMode";
  mode.min = 0, mode.max = 3;  // the items' range, not declared
  v.push_back(mode);
  v.push_back(
      startingAt(variable("use_velocity_inputs", VariableType::Boolean, Causality::Parameter, Variability::Fixed), 1));
  v.push_back(startingAt(variable("steps", VariableType::Integer, Causality::Parameter, Variability::Fixed), -7));
  Variable gain = startingAt(
      variable("controller.joint_a.ki", VariableType::Real, Causality::Parameter, Variability::Fixed, "N.m/(rad.s)"),
      0.1);
  gain.has_min = true, gain.min = 5e-324;
  gain.description = "integral gain <ki> & \"more\"\nsecond line\ttab";
  v.push_back(gain);
  for (const std::string joint : {"joint_a", "'joint b'"}) {
    Variable q =
        startingAt(variable("q_desired." + joint, VariableType::Real, Causality::Input, Variability::Continuous, "rad"),
                   1.0 / 3.0);
    q.has_min = q.has_max = true, q.min = -2.5, q.max = 1e16;
    v.push_back(q);
  }
  for (const std::string joint : {"joint_a", "'joint b'"})
    v.push_back(startingAt(
        variable("qdd_desired." + joint, VariableType::Real, Causality::Input, Variability::Continuous, "rad/s2"),
        -0.0));
  for (int j = 0; j < 2; ++j) {
    Variable ref = variable(std::string("q_ref.") + (j ? "'joint b'" : "joint_a"), VariableType::Real,
                            Causality::Output, Variability::Continuous, "rad");
    ref.depends = {5 + j, 7, 8};  // its own q_desired and both accelerations
    v.push_back(ref);
  }
  v.push_back(variable("q_link.joint_a", VariableType::Real, Causality::Output, Variability::Continuous, "rad"));
  for (std::size_t i = 0; i < v.size(); ++i) v[i].vr = static_cast<std::uint32_t>(i);
  return t;
}

std::string scratchFile(const std::string& name, const std::string& contents) {
  std::filesystem::create_directories(JOINTCOMP_FMU_SCRATCH_DIR);
  const std::string path = std::string(JOINTCOMP_FMU_SCRATCH_DIR) + "/" + name;
  std::ofstream(path, std::ios::binary) << contents;
  return path;
}

// ElementTree's reading of the XML, with the ModelStructure by variable name.
constexpr const char* kReader = R"(
import json, sys, xml.etree.ElementTree as ET
root = ET.parse(sys.argv[1]).getroot()
fmi2 = root.get('fmiVersion') == '2.0'
out = {'token': root.get('guid' if fmi2 else 'instantiationToken'), 'description': root.get('description'),
       'units': [u.get('name') for u in root.iter('Unit')], 'variables': {}, 'outputs': {}, 'initial': []}
variables = root.find('ModelVariables')
elements = [(sv.get('name'), sv.attrib, sv[0].tag, sv[0].attrib) for sv in variables] if fmi2 else \
           [(e.get('name'), e.attrib, e.tag, e.attrib) for e in variables]
names = [e[0] for e in elements]
by_vr = {int(a['valueReference']): n for n, a, _, _ in elements}
for name, attributes, tag, typed in elements:
    out['variables'][name] = {'vr': int(attributes['valueReference']), 'causality': attributes.get('causality'),
        'description': attributes.get('description', ''), 'tag': tag,
        **{k: typed[k] for k in ('start', 'min', 'max', 'unit', 'declaredType') if k in typed}}
structure = root.find('ModelStructure')
if fmi2:
    name_of = lambda k: names[int(k) - 1]
    outputs, initial = structure.find('Outputs'), structure.find('InitialUnknowns')
    out['outputs'] = {name_of(u.get('index')): [name_of(k) for k in u.get('dependencies').split()] for u in outputs}
    out['initial'] = [name_of(u.get('index')) for u in initial]
else:
    out['outputs'] = {by_vr[int(u.get('valueReference'))]: [by_vr[int(k)] for k in u.get('dependencies').split()]
                      for u in structure.findall('Output')}
    out['initial'] = [by_vr[int(u.get('valueReference'))] for u in structure.findall('InitialUnknown')]
print(json.dumps(out))
)";

nlohmann::json readBack(const std::string& xml_path) {
  const test::ChildResult read = test::runChild({kPython, "-c", kReader, xml_path});
  EXPECT_EQ(read.exit_code, 0) << read.why << read.output;
  return nlohmann::json::parse(read.output);
}

class ModelDescriptionXml : public ::testing::TestWithParam<int> {};

TEST_P(ModelDescriptionXml, ValidatesAgainstTheFmiSchema) {
  const int version = GetParam();
  const std::string schema =
      "fmi-schema/fmi" + std::to_string(version) + "/fmi" + std::to_string(version) + "ModelDescription.xsd";
  JOINTCOMP_REQUIRE_SHARED_FILE("the FMI schema", schema);
  const std::string path =
      scratchFile("two_joints_fmi" + std::to_string(version) + ".xml", modelDescriptionXml(twoJointTable(), version));
  const test::ChildResult lint =
      test::runChild({"/usr/bin/xmllint", "--noout", "--schema", test::sharedFile(schema), path});
  EXPECT_EQ(lint.exit_code, 0) << lint.why << lint.output;
}

TEST_P(ModelDescriptionXml, ReadsBackAsTheTable) {
  const int version = GetParam();
  const VariableTable table = twoJointTable();
  const nlohmann::json xml =
      readBack(scratchFile("read_fmi" + std::to_string(version) + ".xml", modelDescriptionXml(table, version)));
  EXPECT_EQ(xml["token"], table.instantiation_token);
  EXPECT_EQ(xml["description"], table.model.description);
  // Only the units in use, each once.
  EXPECT_EQ(xml["units"], (std::vector<std::string>{"s", "rad", "rad/s2", "N.m/(rad.s)"}));
  ASSERT_EQ(xml["variables"].size(), table.variables.size());
  for (const Variable& v : table.variables) {
    const nlohmann::json& read = xml["variables"].at(v.name);
    EXPECT_EQ(read["vr"], v.vr) << v.name;
    EXPECT_EQ(read.value("description", ""), v.description) << v.name;
    EXPECT_EQ(read.value("unit", ""), v.unit) << v.name;
    if (v.type == VariableType::Real && v.has_start) {  // the text reads back to the same double
      const double start = readDouble(read["start"].get<std::string>());
      EXPECT_EQ(start, v.start) << v.name;
      EXPECT_EQ(std::signbit(start), std::signbit(v.start)) << v.name;
    }
    if (v.has_min) {
      EXPECT_EQ(readDouble(read["min"].get<std::string>()), v.min) << v.name;
    }
    if (v.has_max) {
      EXPECT_EQ(readDouble(read["max"].get<std::string>()), v.max) << v.name;
    }
    if (!v.has_start) {
      EXPECT_FALSE(read.contains("start")) << v.name;
    }
  }
  // An enumeration's items' range is not declared; Booleans and integers as FMI writes them.
  EXPECT_FALSE(xml["variables"]["compensation"].contains("min"));
  EXPECT_FALSE(xml["variables"]["compensation"].contains("max"));
  EXPECT_EQ(xml["variables"]["compensation"]["declaredType"], "CompensationMode");
  EXPECT_EQ(xml["variables"]["compensation"]["start"], "3");
  EXPECT_EQ(xml["variables"]["use_velocity_inputs"]["start"], "true");
  EXPECT_EQ(xml["variables"]["steps"]["start"], "-7");
  EXPECT_EQ(xml["variables"]["steps"]["tag"], version == 2 ? "Integer" : "Int32");
  EXPECT_EQ(xml["variables"]["time"]["tag"], version == 2 ? "Real" : "Float64");
  // Every output with exactly its direct dependencies, by name.
  std::map<std::string, std::vector<std::string>> expected;
  std::vector<std::string> outputs;
  for (const Variable& v : table.variables) {
    if (v.causality != Causality::Output) continue;
    outputs.push_back(v.name);
    for (const int k : v.depends) expected[v.name].push_back(table.variables[static_cast<std::size_t>(k)].name);
    expected[v.name];  // an output without dependencies has an empty list
  }
  EXPECT_EQ(xml["outputs"].get<decltype(expected)>(), expected);
  EXPECT_EQ(xml["initial"].get<std::vector<std::string>>(), outputs);
}

INSTANTIATE_TEST_SUITE_P(Fmi, ModelDescriptionXml, ::testing::Values(2, 3),
                         [](const ::testing::TestParamInfo<int>& param) {
                           return "Fmi" + std::to_string(param.param);
                         });

TEST(RealText, IsWhatPythonsReprWritesAndReadsBackExactly) {
  const std::vector<double> values = {0.0,
                                      -0.0,
                                      1.0,
                                      30.0,
                                      0.001,
                                      1e-4,
                                      1e-5,
                                      0.1,
                                      1.0 / 3,
                                      1e15,
                                      1e16,
                                      1.5e16,
                                      -2.5,
                                      123456789012345680.0,
                                      5e-324,
                                      1e-300,
                                      1.7976931348623157e308,
                                      2.2250738585072014e-308,
                                      100000.0,
                                      12345.678,
                                      -1e-7,
                                      0.5e22};
  std::string arguments, texts;
  std::vector<std::string> argv = {kPython, "-c", "import sys\nfor a in sys.argv[1:]: print(repr(float.fromhex(a)))"};
  for (const double value : values) {
    char hex[64];
    std::snprintf(hex, sizeof hex, "%a", value);
    argv.push_back(hex);
    texts += realText(value) + "\n";
    EXPECT_EQ(readDouble(realText(value)), value) << realText(value);
  }
  const test::ChildResult python = test::runChild(argv);
  ASSERT_EQ(python.exit_code, 0) << python.why << python.output;
  EXPECT_EQ(texts, python.output);
  EXPECT_THROW(realText(std::numeric_limits<double>::infinity()), Error);
  EXPECT_THROW(realText(std::nan("")), Error);
}

TEST(XmlAttribute, EscapesAsPythonsQuoteattr) {
  const std::vector<std::string> texts = {
      "plain", "a<b>&c", "say \"hi\"", "it's \"both\"", "line\nbreak\ttab\r", "N.m/(rad.s)", "\xc3\xa9t\xc3\xa9"};
  std::vector<std::string> argv = {kPython, "-c",
                                   "import sys\nfrom xml.sax.saxutils import quoteattr\n"
                                   "for a in sys.argv[1:]: sys.stdout.write(quoteattr(a) + '\\x00')"};
  std::string expected;
  for (const std::string& text : texts) {
    argv.push_back(text);
    expected += xmlAttribute(text, "test") + std::string(1, '\0');
  }
  const test::ChildResult python = test::runChild(argv);
  ASSERT_EQ(python.exit_code, 0) << python.why << python.output;
  EXPECT_EQ(expected, python.output);
}

TEST(ModelDescriptionXmlRefuses, WhatXmlCannotCarryNamingTheVariable) {
  const auto refused = [](VariableTable table, int version, const std::string& named) {
    try {
      modelDescriptionXml(table, version);
      ADD_FAILURE() << "accepted; expected an error naming " << named;
    } catch (const Error& error) {
      EXPECT_NE(std::string(error.what()).find(named), std::string::npos) << error.what();
    }
  };
  refused(twoJointTable(), 4, "FMI version 4");
  VariableTable table = twoJointTable();
  table.variables[4].start = std::numeric_limits<double>::infinity();
  refused(table, 2, "controller.joint_a.ki");
  table = twoJointTable();
  table.variables[3].start = 0.5;  // an integer
  refused(table, 3, "'steps'");
  table = twoJointTable();
  table.variables[4].description = "bad \xff byte";
  refused(table, 2, "controller.joint_a.ki");
  table = twoJointTable();
  table.variables[4].description = std::string("bell \x07");
  refused(table, 3, "U+0007");
  table = twoJointTable();
  table.variables[9].depends = {10};  // q_ref.'joint b', an output, not an input
  refused(table, 2, "q_ref.joint_a");
  table = twoJointTable();
  table.variables[9].depends = {99};
  refused(table, 3, "q_ref.joint_a");
  table = twoJointTable();
  table.variables[5].unit = "furlong";
  refused(table, 2, "furlong");
}

TEST(VariablesHtml, ListsEveryVariableEscaped) {
  const VariableTable table = twoJointTable();
  const std::string html = variablesHtml(table);
  for (const Variable& v : table.variables) {
    std::string escaped;
    for (const char c : v.name) escaped += c == '\'' ? std::string("&#x27;") : std::string(1, c);
    EXPECT_NE(html.find("<td>" + escaped + "</td>"), std::string::npos) << v.name;
  }
  EXPECT_NE(html.find("integral gain &lt;ki&gt; &amp; &quot;more&quot;"), std::string::npos);
  EXPECT_NE(html.find("dynamic = 3 (a &lt; b)"), std::string::npos);
}

}  // namespace
}  // namespace jointcomp::fmu
