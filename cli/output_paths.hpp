// Where a command writes, checked before it computes anything: a long calibration must not end with "cannot
// write" because --out named a file, a read-only folder or a path nobody can create.
#pragma once

#include <cstddef>
#include <string>

namespace jointcomp::cli {

// Makes `folder` (and its parents) if needed and proves it writable by creating and removing a file in
// it. Throws std::invalid_argument naming `option` ("--out"), the path and the reason otherwise.
void prepareOutputFolder(const std::string& folder, const std::string& option = "--out");

// The folders prepareOutputFolder and prepareOutputFile made, removed again when still empty: what a refused
// run calls (cli/main.cpp) so that it leaves no empty --out folder behind. Folders that existed are kept.
void removeCreatedEmptyFolders();

// The same for a file to be written: its folder must be preparable and the path must not be a folder.
void prepareOutputFile(const std::string& file, const std::string& option = "--out");

// A name taken from the user's data (a robot's name in its URDF) as one plain file name inside --out:
// letters, digits, '.', '_' and '-' kept, anything else '_', no leading dot (never ".", ".." or a hidden
// file), at most kMaxPlainNameLength characters; `fallback` when nothing is left. "../../victim" ->
// "_.._victim". The same rule as capi/python/jointcomp/_paths.py.
constexpr std::size_t kMaxPlainNameLength = 64;
std::string plainFileName(const std::string& text, const std::string& fallback = "robot");

}  // namespace jointcomp::cli
