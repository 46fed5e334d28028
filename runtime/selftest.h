// The known-answer self-test (issue 27, part 4): before its first render on a device, stex renders a small,
// fixed, synthetic model of each kind and path it is about to use and compares the device's bits with the
// C++ reference evaluator's (kernels/shared compiled as C++; every kind has one). A device that differs is
// refused for that path: Error(Device), exit 4, naming the path, the device and both hashes.
//
// Rows. A row is a kind and one of its evaluation paths (the kernel, or kernel variant, a render uses):
//   texton   splat | gather | gather-local [order N] | filtered | mapped (camera, UV map)
//   lrp, gabor, mix [order N]   gather
//   cs-spot  lattice (periods x scale <= 4096 px) | general
//   cs-rpn   random-phase | gabor | phasor | fourier
//   tb       aligned (scale 1) | scaled;  cs-tb  aligned (integer periods, scale 1) | sub-pixel | scaled
//   surface  points
// Each row renders a synthetic model built in code (deterministic: the counter RNG of kernels/shared/rng.h
// keyed by fixed seeds; no files) over two regions, one at the origin's negative side and one far from it
// (x = 10^12 + 3), sometimes with a second model or scale for the path's branches; all bits are compared.
//
// Cache. Results are kept per key (device name, device version, driver version, platform name and version,
// stex version, hash of every kernel source as built, extra test defines) in one file per row under
// $XDG_CACHE_HOME/stex/selftest/<key id>/, else ~/.cache/stex/selftest/<key id>/ (next to the PoCL kernel
// cache of configure_kernel_cache; $STEX_SELFTEST_CACHE/<key id>/ when that is set), written atomically
// (temp file, fsync, rename). A cached pass skips the
// row; a cached failure refuses without re-running (delete the file, or run `stex selftest`, to re-check).
// Device errors while checking (build failures, lost devices) are not cached: they propagate as they are.
#pragma once
#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "runtime/context.h"
#include "runtime/device.h"

namespace stex {

struct SelftestRow {
  std::string kind;  // the model kind ("texton", "cs-tb", ...; "surface" for surface points)
  std::string path;  // the evaluation path ("splat", "gather-local order 3", "aligned", ...)
  std::string name() const { return kind + " " + path; }
  bool operator==(const SelftestRow& o) const { return kind == o.kind && path == o.path; }
};

struct SelftestResult {
  SelftestRow row;
  bool pass = false;
  bool cached = false;      // read from the cache, not run now
  double ms = 0.0;          // wall time of the check (device and reference renders)
  std::string expected;     // hash of the C++ reference's output bits (16 hex digits), "" if not run
  std::string actual;       // hash of the device's output bits
  std::size_t values = 0;   // values compared
  std::size_t differing = 0;  // of which differ bit for bit
  std::string error;        // why it failed ("" on a pass)
  std::string note;         // e.g. the strategy that actually ran when the device made the renderer fall back
  // stex refuses this path on this device up front (the renderer's Error(Device) that is not an OpenCL error,
  // e.g. the splat on rusticl): the reason. Not a failure of the bits: a render of the path exits 4 with it
  // anyway, so `stex selftest` counts it as no failure. Never cached.
  std::string refused;
  std::string file;         // the cache file (when read from or written to the cache)
};

// Every row `stex selftest` runs on a device (texton's order-3 row uses the strategy `auto` picks there).
std::vector<SelftestRow> selftest_rows(const DeviceInfo& device);

// The texton strategy a render with `strategy` runs on `device`, as TextonRenderer::resolve decides it: `auto`
// is splat on CPUs, gather-local on GPUs, gather elsewhere; gather-local is the gather on a device without
// local memory.
std::string texton_selftest_strategy(const std::string& strategy, const DeviceInfo& device);

// The row of a filtered texton render (runtime/texton_filter.h): "filtered" for the flat plane at a scale,
// "mapped" for a camera or a UV map.
SelftestRow filtered_selftest_row(bool mapped);

// The texton row of a strategy name ("splat", "gather", "gather-local") and order: "splat", "splat order 3".
SelftestRow texton_selftest_row(const std::string& strategy, int order);

// Runs one row on ctx's device, uncached. A mismatch is a result with pass = false; a path stex refuses on
// this device is a result with `refused` set; other errors propagate (OpenCL errors, build failures: stex::Error).
// Error(Usage) for an unknown row.
SelftestResult run_selftest_row(Context& ctx, const SelftestRow& row);

// A result as one line of JSON (kind, path, pass, ms, expected, actual, values, differing, error, note, time),
// as the cache files and the child processes of `stex selftest` carry it, and back (Error(Internal) when
// malformed).
std::string selftest_result_json(const SelftestResult& result);
SelftestResult selftest_result_from_json(const std::string& text);

// FNV-1a 64 of the values' bits, as 16 hex digits: the hashes the self-test reports.
std::string selftest_hash(const std::vector<float>& values);

// The cache key of a device.
struct SelftestKey {
  std::string device, device_version, driver, platform, platform_version, version, kernels, defines;
  std::string id() const;  // 16 hex digits naming the key's directory
};
SelftestKey selftest_key(const DeviceInfo& device);
// Hash of every embedded kernel source with its includes resolved (honours STEX_KERNEL_DIR); computed once.
std::string kernel_sources_hash();
// The cache's root directory: $STEX_SELFTEST_CACHE, else $XDG_CACHE_HOME/stex/selftest, else
// $HOME/.cache/stex/selftest; "" when none is set (no caching then).
std::string selftest_cache_dir();
// The cached result of a row, if any (a damaged file counts as none).
std::optional<SelftestResult> read_selftest_cache(const SelftestKey& key, const SelftestRow& row);
// Stores a result atomically; returns the file, "" when there is no cache directory or it cannot be written
// (an unwritable cache only costs a re-run).
std::string write_selftest_cache(const SelftestKey& key, const SelftestResult& result);

// The message of a failed row: path, device (name, platform, driver version), expected and actual hashes.
std::string selftest_failure_message(const DeviceInfo& device, const SelftestResult& result);

// The gate before a render: every row must pass, from the cache or by running it now (and caching the
// result). A failure throws Error(Device) with selftest_failure_message. Rows that passed once in this
// process are not looked up again (thread-safe). Returns the rows it ran now (not from the cache or memo).
std::vector<SelftestResult> ensure_selftest(Context& ctx, const std::vector<SelftestRow>& rows);

// The results ensure_selftest met in this process for this device's key (run now or read from the cache; passes
// and failures), in the order first met. `stex serve` reports them in /api/health.
std::vector<SelftestResult> selftest_seen(const DeviceInfo& device);

// Extra kernel build options for test builds: the value of STEX_TEST_KERNEL_DEFINES (only "-D..." words)
// when the runtime is compiled with STEX_TESTING (CMake option STEX_TESTING), else "". Program appends them
// to every build; kernels/shared/rng.h's STEX_FAULT_FLIP_RNG_BIT is what the tests pass.
std::string test_kernel_defines();
// Whether this build honours STEX_TEST_KERNEL_DEFINES.
bool test_kernel_defines_supported();

}  // namespace stex
