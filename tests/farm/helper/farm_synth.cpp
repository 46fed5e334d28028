// farm_synth: a test-only renderer of a synthetic pattern through farm::run, with exactly the farm options
// of `stex render`. It keeps the farm tests (subprocesses, kill -9, concurrency, full filesystems, Slurm)
// independent of the OpenCL texton renderer: every pixel is a pure integer hash of (seed, x, y, channel),
// so tiles rendered by any process join bit for bit, like real renders.
//   farm_synth [MODEL] -o 'out/t_{tx}_{ty}.exr' --size 1024x1024 --tile-size 256 [--seed N] [--channels C]
//              [--origin X,Y] [--sleep-ms N] [--fail-at-x X] [farm options]
#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <thread>

#include "core/error.h"
#include "farm/batch.h"
#include "farm/farm_cli.h"
#include "farm/output_file.h"
#include "tests/farm/synth_pattern.h"

int main(int argc, char** argv) {
  CLI::App app{"farm_synth: synthetic farm renderer for tests"};
  stex::farm::FarmOptions farm;
  std::string output, size = "256x256", origin = "0,0";
  std::uint64_t seed = 1;
  int channels = 3, bits = 0, sleep_ms = 0;
  long long fail_tile = -1;
  bool quiet = false;
  std::string model;
  app.add_option("model", model, "optional: any file standing in for a model; its name joins the model hash");
  app.add_option("-o,--output", output);
  app.add_option("--size", size);
  app.add_option("--origin", origin);
  app.add_option("--seed", seed);
  app.add_option("--channels", channels);
  app.add_option("--bits", bits);
  app.add_option("--sleep-ms", sleep_ms, "sleep per rendered tile (widens the kill -9 window)");
  app.add_option("--fail-at-x", fail_tile,
                 "throw Error(Retryable) when rendering a region whose image x0 is this");
  app.add_flag("-q,--quiet", quiet);
  std::vector<std::string> check_equal;
  app.add_option("--check-equal", check_equal,
                 "instead of rendering: exit 0 when the two images hold bit-identical pixels, else 1")
      ->expected(2);
  stex::farm::add_farm_options(&app, farm);
  try {
    app.parse(argc, argv);
    if (!check_equal.empty()) {
      std::vector<float> a = stex::farm::read_output_pixels(check_equal[0]);
      std::vector<float> b = stex::farm::read_output_pixels(check_equal[1]);
      bool same = a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
      std::printf("%s and %s: %s\n", check_equal[0].c_str(), check_equal[1].c_str(),
                  same ? "identical pixels" : "pixels DIFFER");
      return same ? 0 : 1;
    }
    if (output.empty()) throw stex::Error(stex::ErrorKind::Usage, "-o is required");
    long long w = 0, h = 0, ox = 0, oy = 0;
    if (std::sscanf(size.c_str(), "%lldx%lld", &w, &h) != 2)
      throw stex::Error(stex::ErrorKind::Usage, "bad --size");
    if (std::sscanf(origin.c_str(), "%lld,%lld", &ox, &oy) != 2)
      throw stex::Error(stex::ErrorKind::Usage, "bad --origin");
    if (farm.tile_size == 0) farm.tile_size = int(std::max(w, h));
    farm.quiet = quiet;
    stex::farm::RenderJob job;
    job.width = w;
    job.height = h;
    job.channels = channels;
    job.origin_x = ox;
    job.origin_y = oy;
    job.output = output;
    job.model_hash =
        "synthetic-hash-pattern-v1" + (model.empty() ? "" : ":" + model.substr(model.find_last_of('/') + 1));
    job.seed = seed;
    job.mni = 0.0;
    job.params = {{"pattern", "hash"}, {"channels", std::to_string(channels)}};
    job.settings.bits = bits;
    const long long fail_x = fail_tile >= 0 ? fail_tile : -1;
    auto renderer = [&](std::int64_t x0, std::int64_t y0, int tw, int th, std::vector<float>& out) {
      if (fail_x >= 0 && x0 - ox == fail_x)
        throw stex::Error(stex::ErrorKind::Retryable,
                          "synthetic device failure at x = " + std::to_string(x0));
      stex::farm::test::synth_region(seed, channels, x0, y0, tw, th, out);
      if (sleep_ms > 0) std::this_thread::sleep_for(std::chrono::milliseconds(sleep_ms));
    };
    stex::farm::run(farm, job, renderer);
  } catch (const CLI::ParseError& e) {
    int rc = app.exit(e);
    return rc == 0 ? 0 : 2;
  } catch (const stex::Error& e) {
    std::fprintf(stderr, "farm_synth: error: %s\n", e.what());
    return e.exit_code();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "farm_synth: internal error: %s\n", e.what());
    return 1;
  }
  return 0;
}
