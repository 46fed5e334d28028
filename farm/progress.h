// Progress of a farm run. Modes: `bar` (one redrawn line with a bar, tiles, rate and ETA; the default on a
// terminal), `lines` (one line per tile, flushed: the default when stderr is a file or pipe, as in
// scheduler logs), `openjd` (OpenJD's `openjd_progress: <percent>` and `openjd_status: ...` lines on
// stdout, which the OpenJD runtime turns into task progress), `none`.
#pragma once
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <string>

namespace stex::farm {

enum class ProgressMode { Auto, Bar, Lines, OpenJD, None };

// "auto", "bar", "lines", "openjd", "none"; Error(Usage) otherwise.
ProgressMode parse_progress_mode(const std::string& text);

class Progress {
 public:
  // Auto resolves to Bar when `err` is a terminal, else Lines. `out` receives OpenJD lines.
  Progress(ProgressMode mode, std::int64_t total_tiles, std::FILE* err = stderr, std::FILE* out = stdout);

  ProgressMode mode() const { return mode_; }
  // One tile finished (rendered or skipped). `what` names it (its path) for the line mode.
  void tile_finished(std::int64_t tile_index, const std::string& what, bool skipped);
  // Ends the bar line.
  void finish();

  // Seconds per rendered tile so far and the estimated seconds left (-1 when unknown).
  double eta_seconds() const;

 private:
  void draw_bar();
  ProgressMode mode_;
  std::int64_t total_, finished_ = 0, rendered_ = 0;
  std::FILE* err_;
  std::FILE* out_;
  std::chrono::steady_clock::time_point start_;
  bool drew_ = false;
};

// "1:02:03", "2:03", "7 s"-style durations for humans.
std::string format_duration(double seconds);

}  // namespace stex::farm
