// Atomic file creation: a unique temp file beside the target (mkstemps), written, fsynced and renamed over
// the target, so that every file stex writes appears whole or not at all (DESIGN "Invariants";
// FIELD-NOTES: fixed temp names corrupted 56/200 tiles, mkstemp + fsync + rename corrupted 0/200).
#pragma once
#include <cstddef>
#include <string>

namespace stex {

// Creates an empty unique file "DIR/.NAME.tmp-XXXXXX<suffix>" beside `target` and returns its path.
// `suffix` keeps the extension for writers that choose the format by name. Error(Output) on failure.
std::string create_temp_beside(const std::string& target, const std::string& suffix = "");

// Sets mode 0644, fsyncs `tmp`, renames it over `target`, fsyncs the directory (best effort).
// On failure removes `tmp` and throws Error(Output) naming `target`.
void commit_temp(const std::string& tmp, const std::string& target);

// Writes `size` bytes to `target` atomically (create_temp_beside + write + commit_temp).
void write_file_atomic(const std::string& target, const void* data, std::size_t size);

}  // namespace stex
