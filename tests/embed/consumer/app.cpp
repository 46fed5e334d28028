// The consumer test's C++ program: analyses an exemplar, renders a region, checks that point queries at
// the pixel centres equal it bit for bit, prints the mean. Exit 0 on success. Uses only <stex/stex.hpp>.
#include <cstdio>
#include <cstring>
#include <stex/stex.hpp>
#include <vector>

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: consumer_app EXEMPLAR\n");
    return 2;
  }
  try {
    stex::Context ctx;
    stex::AnalysisParams a;
    a.support = 16;
    a.iterations = 4;
    const stex::Model model = stex::Model::analyse(argv[1], a);
    stex::RenderParams p;
    p.seed = 5;
    const int w = 48, h = 32;
    const std::vector<float> img = ctx.render(model, p, 1000, -2000, w, h);
    std::vector<double> xy;
    for (int j = 0; j < h; ++j)
      for (int i = 0; i < w; ++i) xy.insert(xy.end(), {1000 + i + 0.5, -2000 + j + 0.5});
    const std::vector<float> pts = ctx.eval_points(model, p, xy);
    if (pts.size() != img.size() || std::memcmp(pts.data(), img.data(), img.size() * sizeof(float)) != 0) {
      std::fprintf(stderr, "consumer_app: point queries differ from the render\n");
      return 1;
    }
    double sum = 0.0;
    for (float v : img) sum += v;
    std::printf("consumer_app: stex %s on '%s', %dx%d mean %.6f\n", stex::version().c_str(),
                ctx.device_name().c_str(), w, h, sum / double(img.size()));
    return 0;
  } catch (const stex::Error& e) {
    std::fprintf(stderr, "consumer_app: %s: %s\n", e.status_name(), e.what());
    return 1;
  }
}
