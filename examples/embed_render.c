/* embed_render.c: the smallest C program that embeds stex (docs/embedding.md). Creates a context on the
 * default OpenCL device (or the one DEVICE names), loads a model (.stex) or analyses an exemplar image,
 * renders a 256 x 256 region into its own memory, and prints the mean per channel; then evaluates one point
 * query at a pixel centre, which equals the rendered pixel exactly.
 *
 *   embed_render data/gravel.png [DEVICE]   (or a model file written by `stex analyze`; DEVICE as --device)
 *
 * Build: link with the CMake target stex::stex (find_package(stex)), or `cc embed_render.c -lstex`. */
#include <stdio.h>
#include <stdlib.h>
#include <stex/stex.h>
#include <string.h>

/* Prints the failed call's status and message and returns 1 (the process exit code). */
static int report(const char* what, stex_status status) {
  fprintf(stderr, "embed_render: %s failed: %s: %s\n", what, stex_status_name(status), stex_last_error());
  return 1;
}

static int ends_with(const char* s, const char* suffix) {
  size_t n = strlen(s), m = strlen(suffix);
  return n >= m && strcmp(s + n - m, suffix) == 0;
}

int main(int argc, char** argv) {
  enum { kSize = 256 };
  stex_context* ctx = NULL;
  stex_model* model = NULL;
  stex_model_info info;
  stex_render_params params;
  stex_status status;
  float* pixels = NULL;
  double xy[2], sum[4] = {0, 0, 0, 0};
  float point[4];
  int c, exit_code = 1;
  size_t i;
  const char* device_name = NULL;

  if (argc != 2 && argc != 3) {
    fprintf(stderr, "usage: embed_render EXEMPLAR_IMAGE|MODEL.stex [DEVICE]\n");
    return 2;
  }
  /* NULL or "": the default device; else "cpu", "gpu", an index or a name substring. */
  status = stex_context_create(argc == 3 ? argv[2] : NULL, &ctx);
  if (status != STEX_OK) return report("stex_context_create", status);
  stex_context_device_name(ctx, &device_name);

  if (ends_with(argv[1], ".stex"))
    status = stex_model_load(argv[1], &model);
  else
    status = stex_model_analyse_file(argv[1], NULL, &model); /* NULL: default analysis parameters */
  if (status != STEX_OK) {
    exit_code = report("loading/analysing the model", status);
    goto done;
  }
  info.struct_size = sizeof info;
  stex_model_get_info(model, &info);

  stex_render_params_init(&params, sizeof params);
  params.seed = 1;
  pixels = (float*)malloc(sizeof(float) * kSize * kSize * (size_t)info.channels);
  if (!pixels) goto done;
  /* The region [-128, 128)^2; row stride 0 = packed rows of kSize * channels floats. */
  status = stex_render(ctx, model, &params, -128, -128, kSize, kSize, pixels, 0, NULL, NULL);
  if (status != STEX_OK) {
    exit_code = report("stex_render", status);
    goto done;
  }
  for (i = 0; i < (size_t)kSize * kSize; ++i)
    for (c = 0; c < info.channels; ++c) sum[c] += pixels[i * (size_t)info.channels + (size_t)c];

  /* Pixel (10, 20) of the image is output pixel (-118, -108); its centre is (-117.5, -107.5). */
  xy[0] = -117.5;
  xy[1] = -107.5;
  status = stex_eval_points(ctx, model, &params, 1, xy, point);
  if (status != STEX_OK) {
    exit_code = report("stex_eval_points", status);
    goto done;
  }

  printf("embed_render: stex %s on '%s', %dx%d, %d channel(s), support %d\n", stex_version_string(),
         device_name, kSize, kSize, info.channels, info.support);
  for (c = 0; c < info.channels; ++c)
    printf("  channel %d: model mean %.4f, render mean %.4f\n", c, info.mean[c], sum[c] / (kSize * kSize));
  printf("  point query at (-117.5, -107.5) %s the rendered pixel\n",
         memcmp(point, &pixels[(20 * kSize + 10) * (size_t)info.channels],
                sizeof(float) * (size_t)info.channels) == 0
             ? "equals"
             : "DIFFERS FROM");
  exit_code = memcmp(point, &pixels[(20 * kSize + 10) * (size_t)info.channels],
                     sizeof(float) * (size_t)info.channels) == 0
                  ? 0
                  : 1;

done:
  free(pixels);
  stex_model_destroy(model);
  stex_context_destroy(ctx);
  return exit_code;
}
