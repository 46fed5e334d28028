// Viewer test of stex serve (ctest entry serve_viewer): headless Chromium (Debian chromium, loopback only)
// loads the viewer page at a view given by URL (?model=&seed=&mni=&z=&x=&y=), waits for the tiles
// (--virtual-time-budget: virtual time stops while fetches are pending) and takes a screenshot; then pans
// (a second URL, offset by a non-multiple of the tile size; and a drag through the canvas's pointer
// handlers, ?drag=) and zooms out (z = -2: filtered tiles). Each
// screenshot's canvas must equal, pixel for pixel, the same area rendered as ONE region by the region
// endpoint (no tiling): so tiles were drawn, at the right places, and join without seams.
#include <cmath>

#include "model/codecs.h"
#include "kernels/test_texton_common.h"
#include "serve/serve_test_util.h"

namespace stex {
namespace {

namespace fs = std::filesystem;

// The window, and the canvas below the page's 40 px toolbar (index.html), fixed by ?w=&h=: headless
// Chromium lays the page out in a viewport smaller than the window (about 640x457 here) and grows it to the
// window for the capture, which would resize a window-filling canvas after its tiles were drawn.
constexpr int k_width = 640, k_height = 600, k_bar = 40, k_canvas_h = 400;

bool screenshot(const std::string& url, const fs::path& png, const fs::path& work) {
  const fs::path profile = work / "chromium-profile";
  fs::remove_all(profile);
  fs::create_directories(profile);
  fs::remove(png);
  const std::string cmd =
      "chromium --headless --no-sandbox --disable-gpu --disable-quic --no-first-run --disable-background-networking "
      "--disable-component-update --disable-sync --disable-extensions --hide-scrollbars --force-device-scale-factor=1 "
      "--force-color-profile=srgb --user-data-dir='" + profile.string() + "' --window-size=" +
      std::to_string(k_width) + "," + std::to_string(k_height) + " --virtual-time-budget=30000 --screenshot='" +
      png.string() + "' '" + url + "' >'" + (work / "chromium.log").string() + "' 2>&1";
  const int rc = std::system(cmd.c_str());
  return rc == 0 && fs::exists(png);
}

// Compares the screenshot's canvas (below the toolbar) with the region [x, x + w) x [y, y + h) at zoom z.
// `drag` (optional, "DX,DY"): the page drags the view through its pointer handlers after loading, so the
// canvas shows the region at (x - DX, y - DY).
void expect_view_equals_region(test::ServeProcess& s, const fs::path& work, const std::string& tag, int z,
                               std::int64_t x, std::int64_t y, std::int64_t drag_x = 0, std::int64_t drag_y = 0) {
  std::string view = "?model=tex&seed=7&mni=30&z=" + std::to_string(z) + "&x=" + std::to_string(x) +
                     "&y=" + std::to_string(y) + "&w=" + std::to_string(k_width) + "&h=" +
                     std::to_string(k_canvas_h);
  if (drag_x || drag_y) {
    view += "&drag=" + std::to_string(drag_x) + "," + std::to_string(drag_y);
    x -= drag_x;
    y -= drag_y;
  }
  const fs::path shot = work / (tag + ".png");
  ASSERT_TRUE(screenshot("http://127.0.0.1:" + std::to_string(s.port()) + "/" + view, shot, work))
      << test::read_file(work / "chromium.log");
  const int w = k_width, h = k_canvas_h;
  auto c = s.client();
  char scale[64];
  std::snprintf(scale, sizeof scale, "%.17g", std::ldexp(1.0, z));
  auto res = c.Get(("/api/region/tex.png?seed=7&mni=30&x=" + std::to_string(x) + "&y=" + std::to_string(y) +
                    "&w=" + std::to_string(w) + "&h=" + std::to_string(h) + "&scale=" + scale)
                       .c_str());
  ASSERT_TRUE(res && res->status == 200) << (res ? res->body : "no answer");
  const fs::path region_png = work / (tag + "-region.png");
  test::write_file(region_png, res->body);
  const test::Decoded a = test::decode(shot), b = test::decode(region_png);
  ASSERT_EQ(a.width, k_width);
  ASSERT_EQ(a.height, k_height);
  ASSERT_GE(a.channels, 3);
  ASSERT_EQ(b.width, w);
  ASSERT_EQ(b.height, h);
  ASSERT_EQ(b.channels, 3);
  // Exact 8-bit equality per pixel and channel (both decode to k/255), and per tile-border column/row.
  std::size_t mismatched = 0, border_mismatched = 0, borders = 0;
  double sum = 0, sum2 = 0;
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i) {
      const bool border = ((x + i) % 256 == 0) || ((y + j) % 256 == 0);
      borders += border;
      bool same = true;
      for (int ch = 0; ch < 3; ++ch) {
        const float va = a.pixels[(std::size_t(j + k_bar) * a.width + i) * a.channels + ch];
        const float vb = b.pixels[(std::size_t(j) * w + i) * 3 + ch];
        same = same && std::lround(va * 255.0f) == std::lround(vb * 255.0f);
        sum += va;
        sum2 += double(va) * va;
      }
      if (!same) {
        ++mismatched;
        border_mismatched += border;
      }
    }
  const double n = 3.0 * w * h, mean = sum / n, var = sum2 / n - mean * mean;
  std::printf("%s: z=%d view (%lld, %lld): %zu of %d pixels differ from the region (%zu of %zu on tile borders); "
              "canvas mean %.3f, std %.4f\n",
              tag.c_str(), z, (long long)x, (long long)y, mismatched, w * h, border_mismatched, borders, mean,
              std::sqrt(std::max(0.0, var)));
  EXPECT_GT(borders, std::size_t(0));
  EXPECT_EQ(mismatched, 0u) << tag << ": the viewer's canvas differs from the region render";
  EXPECT_GT(std::sqrt(std::max(0.0, var)), 0.005) << tag << ": the canvas looks empty (no tiles drawn)";
}

TEST(ServeViewer, PansZoomsAndTilesJoinWithoutSeams) {
  ASSERT_EQ(std::system("command -v chromium >/dev/null"), 0) << "chromium is missing: run scripts/install-deps.sh";
  const fs::path work = test::fresh_dir("viewer");
  const fs::path models = work / "models";
  fs::create_directories(models);
  {
    TextonModel m = test::synthetic_model(3, 16, 1, 61, 0.01f);
    m.exemplar_name = "none.png";
    m.stex_version = STEX_VERSION_STRING;
    save_model(m, (models / "tex.stex").string());
  }
  test::ServeProcess s(models, {"--queue", "64"}, work);
  ASSERT_TRUE(s.running()) << s.log();
  expect_view_equals_region(s, work, "view", 0, -300, 200);
  expect_view_equals_region(s, work, "panned", 0, -300 + 173, 200 - 91);  // a pan by URL
  expect_view_equals_region(s, work, "dragged", 0, -300, 200, 173, -91);   // a pan by pointer drag
  expect_view_equals_region(s, work, "zoomed-out", -2, -1000, 600);        // filtered tiles (S1 §5)
  EXPECT_EQ(s.stop(), 0) << s.log();
}

}  // namespace
}  // namespace stex
