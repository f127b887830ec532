// Text a user gave (a URDF, a parameter or robot file, a campaign, a CSV export, an IPA file): UTF-8 without
// NUL bytes. A UTF-8 byte-order mark, which Windows editors put first, is skipped (it once made the IPA
// importer say "'Timestamp' is missing"); UTF-16 and UTF-32 text and any NUL byte are refused naming the
// source and the byte offset (a NUL cut the messages quoting the text mid-sentence).
#pragma once

#include <string>

namespace jointcomp {

// Why `text` is not plain UTF-8 text, naming the byte offset ("" when it is).
std::string plainTextProblem(const std::string& text);

// 3 when `text` begins with a UTF-8 byte-order mark, else 0.
std::size_t byteOrderMarkLength(const std::string& text);

// `text` without its byte-order mark (in `storage` when it had one); throws E(source + ": " + problem).
template <class E>
const std::string& plainText(const std::string& text, const std::string& source, std::string& storage) {
  const std::string problem = plainTextProblem(text);
  if (!problem.empty()) throw E(source + ": " + problem);
  const std::size_t skip = byteOrderMarkLength(text);
  if (skip == 0) return text;
  storage = text.substr(skip);
  return storage;
}

}  // namespace jointcomp
