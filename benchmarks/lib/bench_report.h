// Reports of a `stex bench` run (benchmarks/lib/bench_suite.h): the terminal table, S1's Table 1 layout
// (S1 §9: rows 1024^2, HD, 4K; columns texton 64^2 and 256^2; "fps / ms") for the device in use, the goals,
// JSON, CSV, Markdown (the tables of docs/benchmarks.md) and the fps-against-quality plot as SVG (written by
// stex itself: no plotting tool needed). Definitions of every column are in bench_suite.h and quality.h.
#pragma once
#include <string>

#include "benchmarks/lib/bench_suite.h"

namespace stex::bench {

std::string format_terminal(const BenchReport& report);  // machine, points table, Table 1, goals, notes
std::string format_table1(const BenchReport& report);    // "" if the run has none of Table 1's points
std::string format_goals(const BenchReport& report);
std::string to_json(const BenchReport& report);
std::string to_csv(const BenchReport& report);  // one row per (point, strategy)
std::string to_markdown(const BenchReport& report);
// fps against excess kurtosis and against the spectrum error, one curve per texton support (labels: MNI),
// for the first configured output size; the ADSN baseline is marked on the spectrum panel.
std::string to_svg(const BenchReport& report);

}  // namespace stex::bench
