#include "model/common/plain_text.hpp"

#include <cstring>

namespace jointcomp {

namespace {

bool startsWith(const std::string& text, const char* bytes, std::size_t count) {
  return text.size() >= count && std::memcmp(text.data(), bytes, count) == 0;
}

}  // namespace

std::size_t byteOrderMarkLength(const std::string& text) { return startsWith(text, "\xEF\xBB\xBF", 3) ? 3 : 0; }

std::string plainTextProblem(const std::string& text) {
  const char* const save_as = "; save it as UTF-8 text";
  // UTF-32 first: its little-endian mark begins with UTF-16's.
  if (startsWith(text, "\xFF\xFE\x00\x00", 4) || startsWith(text, "\x00\x00\xFE\xFF", 4)) {
    return std::string("bytes 0-3 are a UTF-32 byte-order mark: the text is UTF-32") + save_as;
  }
  if (startsWith(text, "\xFF\xFE", 2) || startsWith(text, "\xFE\xFF", 2)) {
    return std::string("bytes 0-1 are a UTF-16 byte-order mark: the text is UTF-16") + save_as;
  }
  const std::size_t nul = text.find('\0');
  if (nul != std::string::npos) {
    return "byte " + std::to_string(nul) + " is a NUL byte (binary data, or UTF-16 text without its mark?)" + save_as;
  }
  return "";
}

}  // namespace jointcomp
