// modelDescription.xml (FMI 2.0 or 3.0 co-simulation) and the documentation's variable table, written from
// the run-time variable table (variable_table.hpp): what modelDescription/generate.py wrote at build time,
// line for line, now for any robot. Value references are the table's indices; FMI 2's ModelStructure
// refers to variables by their 1-based position, FMI 3's by value reference.
#pragma once

#include <string>

#include "fmu/description/variable_table.hpp"

namespace jointcomp::fmu {

// The whole modelDescription.xml of `table` for FMI `fmi_version` (2 or 3). Throws jointcomp::Error
// naming the variable or attribute at fault for what the XML cannot carry: a version other than 2 or 3,
// a non-finite number, a non-integral integer or enumeration value, text that is not UTF-8 or holds a
// control character XML forbids, a dependency that is no variable of the table.
std::string modelDescriptionXml(const VariableTable& table, int fmi_version);

// documentation/variables.html: every variable with its value reference, causality, variability, type,
// unit, start value and description, and the enumerations' items.
std::string variablesHtml(const VariableTable& table);

// The shortest text that reads back to the same double, as Python's repr writes it ("30.0", "1e-05",
// "0.001", "1.5e+16"). Throws jointcomp::Error for a non-finite value.
std::string realText(double value);

// `text` as an XML attribute value with its quotes, as Python's xml.sax.saxutils.quoteattr writes it:
// &, <, > and line breaks and tabs escaped; in double quotes unless the text holds a double quote and no
// single one. Throws jointcomp::Error naming `what` for text that is not UTF-8 or holds a control
// character XML 1.0 does not allow.
std::string xmlAttribute(const std::string& text, const std::string& what);

}  // namespace jointcomp::fmu
