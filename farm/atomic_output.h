// Atomic output files for farm renders: every file appears whole under its name or not at all (DESIGN
// "Invariants"). A unique temp file is created beside the target (mkstemps, so two processes writing the
// same tile never share a temp file; FIELD-NOTES measured 56/200 corrupt tiles with fixed temp names and
// 0/200 this way), written by the caller, fsynced, renamed over the target, and the directory fsynced.
// A temp file that is not committed is removed when its owner goes away (errors, SIGINT/SIGTERM); only a
// kill -9 or a crash can leave one behind, always under a hidden temp name (is_temp_name()).
#pragma once
#include <string>

namespace stex::farm {

class TempOutput {
 public:
  // Creates "DIR/.NAME.stex-tmp-XXXXXX.EXT" beside `target` (the extension is kept: OIIO chooses the
  // writer by it). Error(Output) naming the directory when it cannot be created there.
  explicit TempOutput(const std::string& target);
  ~TempOutput();
  TempOutput(const TempOutput&) = delete;
  TempOutput& operator=(const TempOutput&) = delete;

  const std::string& path() const { return path_; }
  const std::string& target() const { return target_; }

  // fsync the temp file, rename it over the target, fsync the directory. On failure the temp file is
  // removed and Error(Output) names the target and the system error (e.g. "No space left on device").
  // Test hook: STEX_FARM_FAULT_FSYNC=N makes the N-th commit of the process (1-based) fail as if fsync
  // had returned ENOSPC.
  void commit();
  // Removes the temp file now (idempotent).
  void discard();

 private:
  std::string target_, path_;
  bool done_ = false;
};

// Why a write to `target` may have failed, for messages: the system error when `saved_errno` is one a
// full or broken filesystem gives (ENOSPC, EDQUOT, EIO, EROFS, EFBIG), else "No space left on device"
// when the target's filesystem has (almost) no free space, else "". OIIO's own messages for a failed
// write do not always say why ("Failed to write pixel data").
std::string write_failure_cause(const std::string& target, int saved_errno);

// True for names TempOutput creates (".NAME.stex-tmp-XXXXXX[.EXT]"), given a file name without directory.
bool is_temp_name(const std::string& filename);

// Creates the parent directories of `path` (like mkdir -p); Error(Output) on failure.
void make_parent_dirs(const std::string& path);

}  // namespace stex::farm
