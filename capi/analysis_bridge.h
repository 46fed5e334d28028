// The C interface between libstex.so and libstex_analysis.so (issue 28: a small core). libstex.so renders
// and depends on the OpenCL loader and the C/C++ runtime only; the texton analysis (FFT, image decoding:
// FFTW and OpenImageIO) lives in libstex_analysis.so, which libstex.so loads with dlopen the first time
// stex_model_analyse_file or stex_model_analyse_pixels is called (capi/model.cpp), from the directory that
// holds libstex.so, else from the library search path. An application that only loads and renders models
// never loads it; the C API is the same either way.
//
// The analysis library exports one function, STEX_ANALYSIS_BRIDGE_SYMBOL, and returns the analysed model as
// the bytes of a model file (model/container.h), which libstex.so decodes as stex_model_load does. Arguments
// are already checked by libstex.so. Both libraries come from one build: the symbol's version suffix changes
// whenever this interface does.
#pragma once
#include <stddef.h>
#include <stdint.h>

#include "stex/stex.h"

#ifdef __cplusplus
extern "C" {
#endif

#define STEX_ANALYSIS_BRIDGE_SYMBOL "stex_analysis_bridge_v1"

/* The defaults of stex_analysis_params (stex_analysis_params_init): the analysis's own defaults (TextonParams,
 * LoadOptions), checked against them where the analysis library is compiled. */
#define STEX_ANALYSIS_DEFAULT_PIXEL_BUDGET ((uint64_t)1 << 26)
#define STEX_ANALYSIS_DEFAULT_SUPPORT 64
#define STEX_ANALYSIS_DEFAULT_ITERATIONS 50
#define STEX_ANALYSIS_DEFAULT_ORDER 1
#define STEX_ANALYSIS_DEFAULT_COLOUR_CORRECTION 1

typedef struct stex_analysis_request {
  const char* path;      /* an exemplar file, or NULL for pixels */
  const float* pixels;   /* packed rows: width * channels floats per row */
  int32_t width, height, channels;
  const char* exemplar_name;  /* recorded in the model for pixels ("(memory)") */
  stex_analysis_params params;
} stex_analysis_request;

/* malloc'd by the analysis library, freed by the caller with free(). */
typedef struct stex_analysis_result {
  int32_t status;           /* a stex_status: STEX_OK, else the error's status */
  char* message;            /* the error message (NULL on success) */
  unsigned char* model;     /* the model file's bytes (NULL on error) */
  size_t model_size;
} stex_analysis_result;

typedef void (*stex_analysis_bridge_fn)(const stex_analysis_request* request, stex_analysis_result* result);

#ifdef __cplusplus
}
#endif
