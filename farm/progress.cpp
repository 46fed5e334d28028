// Progress reporting (farm/progress.h).
#include "farm/progress.h"

#include <unistd.h>

#include <cmath>

#include "core/error.h"

namespace stex::farm {

ProgressMode parse_progress_mode(const std::string& t) {
  if (t == "auto") return ProgressMode::Auto;
  if (t == "bar") return ProgressMode::Bar;
  if (t == "lines") return ProgressMode::Lines;
  if (t == "openjd") return ProgressMode::OpenJD;
  if (t == "none") return ProgressMode::None;
  throw Error(ErrorKind::Usage, "--progress '" + t + "': expected auto, bar, lines, openjd or none");
}

std::string format_duration(double s) {
  if (!(s >= 0) || !std::isfinite(s)) return "?";
  long t = long(std::lround(s));
  char buf[32];
  if (t >= 3600)
    std::snprintf(buf, sizeof buf, "%ld:%02ld:%02ld", t / 3600, (t / 60) % 60, t % 60);
  else if (t >= 60)
    std::snprintf(buf, sizeof buf, "%ld:%02ld", t / 60, t % 60);
  else
    std::snprintf(buf, sizeof buf, "%ld s", t);
  return buf;
}

Progress::Progress(ProgressMode mode, std::int64_t total, std::FILE* err, std::FILE* out)
    : mode_(mode), total_(total), err_(err), out_(out), start_(std::chrono::steady_clock::now()) {
  if (mode_ == ProgressMode::Auto) mode_ = ::isatty(::fileno(err_)) ? ProgressMode::Bar : ProgressMode::Lines;
  if (mode_ == ProgressMode::OpenJD) {
    std::fprintf(out_, "openjd_progress: 0\n");
    std::fflush(out_);
  }
}

double Progress::eta_seconds() const {
  if (rendered_ == 0) return -1;
  double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  return elapsed / double(rendered_) * double(total_ - finished_);
}

void Progress::draw_bar() {
  const int width = 30;
  double frac = total_ > 0 ? double(finished_) / double(total_) : 1.0;
  int fill = int(frac * width);
  char bar[width + 1];
  for (int i = 0; i < width; ++i) bar[i] = i < fill ? '#' : '.';
  bar[width] = '\0';
  double eta = eta_seconds();
  std::fprintf(err_, "\r[%s] %lld/%lld tiles %5.1f%%  ETA %s   ", bar, static_cast<long long>(finished_),
               static_cast<long long>(total_), 100.0 * frac,
               finished_ == total_ ? "0 s" : format_duration(eta).c_str());
  std::fflush(err_);
  drew_ = true;
}

void Progress::tile_finished(std::int64_t tile_index, const std::string& what, bool skipped) {
  ++finished_;
  if (!skipped) ++rendered_;
  double pct = total_ > 0 ? 100.0 * double(finished_) / double(total_) : 100.0;
  switch (mode_) {
    case ProgressMode::Bar:
      draw_bar();
      break;
    case ProgressMode::Lines: {
      double eta = eta_seconds();
      std::fprintf(err_, "stex: tile %lld %s (%lld/%lld, %.1f%%, ETA %s): %s\n",
                   static_cast<long long>(tile_index), skipped ? "skipped" : "done",
                   static_cast<long long>(finished_), static_cast<long long>(total_), pct,
                   finished_ == total_ ? "0 s" : format_duration(eta).c_str(), what.c_str());
      std::fflush(err_);
      break;
    }
    case ProgressMode::OpenJD:
      std::fprintf(out_, "openjd_status: tile %lld %s (%lld/%lld)\nopenjd_progress: %.2f\n",
                   static_cast<long long>(tile_index), skipped ? "skipped" : "done",
                   static_cast<long long>(finished_), static_cast<long long>(total_), pct);
      std::fflush(out_);
      break;
    default:
      break;
  }
}

void Progress::finish() {
  if (mode_ == ProgressMode::Bar && drew_) {
    std::fprintf(err_, "\n");
    std::fflush(err_);
  }
}

}  // namespace stex::farm
