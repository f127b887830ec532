// The FMU's ZIP archive, written by our own code: entries stored uncompressed (method 0, which FMI allows),
// each with its CRC-32, its folders as entries of their own before it, and a fixed time stamp (1980-01-01
// 00:00, the earliest ZIP can say), so the same entries give the same bytes. No ZIP64: an archive or an
// entry of 4 GiB or more, or more than 65535 entries, is refused.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace jointcomp::fmu {

struct ArchiveEntry {
  std::string path;         // inside the archive, '/'-separated: "binaries/linux64/jointcomp.so"
  std::string contents;     // the file's bytes
  bool executable = false;  // recorded as mode 0755 (else 0644) for unzip on Unix
};

// CRC-32 as ZIP uses it (ISO 3309, reflected polynomial 0xEDB88320), continued from `crc` (0 to start).
std::uint32_t crc32(const void* data, std::size_t size, std::uint32_t crc = 0);

// The archive's bytes, entries in the order given. Throws jointcomp::Error naming the entry whose path
// is not a plain relative path (empty, absolute, with a backslash, an empty, "." or ".." part, a
// control character), appears twice or clashes with a folder, or that makes the archive too large.
std::string zipArchive(const std::vector<ArchiveEntry>& entries);

// The archive written whole or not at all (model/io/atomic_file.hpp). Throws jointcomp::Error naming the
// path when it cannot be written.
void writeZipArchive(const std::string& path, const std::vector<ArchiveEntry>& entries);

}  // namespace jointcomp::fmu
