#include "fmu/description/fmu_archive.hpp"

#include <algorithm>
#include <array>
#include <set>

#include "model/common/errors.hpp"
#include "model/io/atomic_file.hpp"

namespace jointcomp::fmu {
namespace {

constexpr std::array<std::uint32_t, 256> crcTable() {
  std::array<std::uint32_t, 256> table{};
  for (std::uint32_t n = 0; n < 256; ++n) {
    std::uint32_t c = n;
    for (int k = 0; k < 8; ++k) c = (c & 1u) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
    table[n] = c;
  }
  return table;
}
constexpr std::array<std::uint32_t, 256> kCrcTable = crcTable();

// The ZIP format's fields: little-endian integers.
void put16(std::string& out, std::uint32_t value) {
  out += static_cast<char>(value & 0xFFu);
  out += static_cast<char>((value >> 8) & 0xFFu);
}
void put32(std::string& out, std::uint32_t value) {
  put16(out, value & 0xFFFFu);
  put16(out, value >> 16);
}

constexpr std::uint32_t kLocalHeader = 0x04034b50u, kCentralHeader = 0x02014b50u, kEndOfCentral = 0x06054b50u;
constexpr std::uint32_t kVersionNeeded = 10;  // 1.0: stored entries, no ZIP64
constexpr std::uint32_t kMadeByUnix = (3u << 8) | 20u;
constexpr std::uint32_t kUtf8Names = 1u << 11;  // general purpose flag 11: the names are UTF-8
constexpr std::uint32_t kDosTime = 0, kDosDate = (0u << 9) | (1u << 5) | 1u;  // 1980-01-01 00:00:00
constexpr std::uint64_t kMaxField = 0xFFFFFFFEu;                              // 0xFFFFFFFF would announce ZIP64
constexpr std::size_t kMaxEntries = 0xFFFFu;

// One entry as the archive stores it (folders end with '/', no contents).
struct Stored {
  std::string name;
  const std::string* contents;  // nullptr for a folder
  std::uint32_t mode;           // Unix mode with its file type bits
  std::uint32_t crc = 0;
  std::uint64_t offset = 0;
};

// Throws unless `path` is a plain relative path of a file: parts separated by single '/', none empty,
// "." or "..", no backslash and no control character.
void checkPath(const std::string& path) {
  const std::string what = "FMU archive: entry '" + path + "'";
  if (path.empty()) throw Error("FMU archive: an entry has an empty path");
  if (path.size() > 0xFFFFu) throw Error(what + ": the path is too long");
  if (path.front() == '/') throw Error(what + ": the path is absolute");
  for (const char c : path) {
    if (c == '\\') throw Error(what + ": the path holds a backslash (ZIP separates folders by '/')");
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7F) throw Error(what + ": the path holds a control character");
  }
  std::size_t start = 0;
  while (start <= path.size()) {
    const std::size_t slash = std::min(path.find('/', start), path.size());
    const std::string part = path.substr(start, slash - start);
    if (part.empty() || part == "." || part == "..")
      throw Error(what + ": the path has an empty, '.' or '..' part (a plain relative path is needed)");
    start = slash + 1;
  }
}

bool isAscii(const std::string& text) {
  for (const char c : text) {
    if (static_cast<unsigned char>(c) >= 0x80) return false;
  }
  return true;
}

// The entries with their folders before them, each folder once; a file whose path is a folder of
// another entry, or a path given twice, is refused.
std::vector<Stored> layOut(const std::vector<ArchiveEntry>& entries) {
  std::set<std::string> files, folders;
  for (const ArchiveEntry& entry : entries) {
    checkPath(entry.path);
    if (!files.insert(entry.path).second) throw Error("FMU archive: entry '" + entry.path + "' is given twice");
  }
  std::vector<Stored> stored;
  for (const ArchiveEntry& entry : entries) {
    for (std::size_t slash = entry.path.find('/'); slash != std::string::npos;
         slash = entry.path.find('/', slash + 1)) {
      const std::string folder = entry.path.substr(0, slash);
      if (files.count(folder))
        throw Error("FMU archive: entry '" + folder + "' is a file and the folder of '" + entry.path + "'");
      if (folders.insert(folder).second) stored.push_back(Stored{folder + "/", nullptr, 0040755u});
    }
    stored.push_back(Stored{entry.path, &entry.contents, entry.executable ? 0100755u : 0100644u});
  }
  if (stored.size() > kMaxEntries)
    throw Error("FMU archive: " + std::to_string(stored.size()) + " entries, more than ZIP without ZIP64 holds");
  return stored;
}

// The fields the local and the central header share, from "version needed" to the extra field's length.
void commonFields(std::string& out, const Stored& entry) {
  const std::uint64_t size = entry.contents ? entry.contents->size() : 0;
  put16(out, kVersionNeeded);
  put16(out, isAscii(entry.name) ? 0u : kUtf8Names);
  put16(out, 0);  // stored
  put16(out, kDosTime);
  put16(out, kDosDate);
  put32(out, entry.crc);
  put32(out, static_cast<std::uint32_t>(size));  // compressed size: the same, stored
  put32(out, static_cast<std::uint32_t>(size));
  put16(out, static_cast<std::uint32_t>(entry.name.size()));
  put16(out, 0);  // no extra field
}

void centralDirectory(std::string& out, const std::vector<Stored>& stored) {
  const std::uint64_t start = out.size();
  for (const Stored& entry : stored) {
    put32(out, kCentralHeader);
    put16(out, kMadeByUnix);
    commonFields(out, entry);
    put16(out, 0);                                                   // no comment
    put16(out, 0);                                                   // disk 0
    put16(out, 0);                                                   // internal attributes
    put32(out, (entry.mode << 16) | (entry.contents ? 0u : 0x10u));  // Unix mode, and MS-DOS's folder bit
    put32(out, static_cast<std::uint32_t>(entry.offset));
    out += entry.name;
  }
  const std::uint64_t size = out.size() - start;
  if (out.size() > kMaxField) throw Error("FMU archive: 4 GiB or more, more than ZIP without ZIP64 holds");
  put32(out, kEndOfCentral);
  put16(out, 0);  // this disk
  put16(out, 0);  // the central directory's disk
  put16(out, static_cast<std::uint32_t>(stored.size()));
  put16(out, static_cast<std::uint32_t>(stored.size()));
  put32(out, static_cast<std::uint32_t>(size));
  put32(out, static_cast<std::uint32_t>(start));
  put16(out, 0);  // no comment
}

}  // namespace

std::uint32_t crc32(const void* data, std::size_t size, std::uint32_t crc) {
  const auto* bytes = static_cast<const unsigned char*>(data);
  crc = ~crc;
  for (std::size_t i = 0; i < size; ++i) crc = kCrcTable[(crc ^ bytes[i]) & 0xFFu] ^ (crc >> 8);
  return ~crc;
}

std::string zipArchive(const std::vector<ArchiveEntry>& entries) {
  std::vector<Stored> stored = layOut(entries);
  std::uint64_t total = 0;
  for (const Stored& entry : stored) total += 30 + entry.name.size() + (entry.contents ? entry.contents->size() : 0);
  std::string out;
  if (total < kMaxField) out.reserve(static_cast<std::size_t>(total) + 46 * stored.size() + 22);
  for (Stored& entry : stored) {
    if (entry.contents && entry.contents->size() > kMaxField)
      throw Error("FMU archive: entry '" + entry.name + "' is 4 GiB or more, more than ZIP without ZIP64 holds");
    if (out.size() > kMaxField) throw Error("FMU archive: 4 GiB or more, more than ZIP without ZIP64 holds");
    entry.offset = out.size();
    if (entry.contents) entry.crc = crc32(entry.contents->data(), entry.contents->size());
    put32(out, kLocalHeader);
    commonFields(out, entry);
    out += entry.name;
    if (entry.contents) out += *entry.contents;
  }
  centralDirectory(out, stored);
  return out;
}

void writeZipArchive(const std::string& path, const std::vector<ArchiveEntry>& entries) {
  writeFileAtomically(path, zipArchive(entries));
}

}  // namespace jointcomp::fmu
