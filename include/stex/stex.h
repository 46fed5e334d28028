/* stex.h: the public C API of stex (libstex.so), for applications that embed stex as a texture-noise
 * backend. It turns an exemplar image into a compact texton noise model and evaluates that model as an
 * unbounded, seamless, deterministic texture on an OpenCL device: regions into caller memory or into a
 * caller's OpenCL buffer, point queries, and surface-noise point queries (positions with tangent frames). It
 * loads and renders model files of every kind stex renders (texton, lrp, gabor, ...). docs/embedding.md is
 * the guide; this header is the reference.
 *
 * ABI. The interface is C99, stable within one SOVERSION (0 while the ABI is pre-1.0: libstex.so.0).
 * Handles are opaque pointers; parameter structs start with a `struct_size` field so that later versions
 * can append fields: fill them with the matching *_init function, then change the fields you need.
 * This header needs no OpenCL header: the interop functions take `struct _cl_context*` etc., which are the
 * types OpenCL's cl_context, cl_device_id, cl_command_queue and cl_mem stand for (pass those directly).
 *
 * Errors. Every function that can fail returns a stex_status; no C++ exception ever crosses this boundary.
 * On failure stex_last_error() describes what failed, on the calling thread. Output handles are set to
 * NULL on failure. Destroy functions accept NULL.
 *
 * Coordinates. Output pixel (i, j), i and j signed 64-bit integers, covers [i, i + 1) x [j, j + 1) and has
 * its centre at (i + 0.5, j + 0.5). The texture is defined on the whole plane: any region and any point
 * with |coordinate| < 2^46 can be evaluated, with the same precision everywhere.
 *
 * Thread safety.
 *  - All functions may be called from any thread.
 *  - A stex_context may be shared by several threads: calls on one context that use its device (render,
 *    render into cl_mem, point queries) are serialised by a lock inside the context, in the order they
 *    acquire it, and run on its single in-order command queue. For parallel device work, use one context
 *    per thread (e.g. one per device).
 *  - A stex_model is immutable after creation: any number of threads and contexts may use it at once.
 *  - Destroying a handle while another call uses it is the caller's error (as with free()).
 *  - stex_last_error() is per thread.
 *  - A progress callback runs on the calling thread while the context's lock is held: it must not call
 *    stex functions on the same context (it may use other contexts).
 */
#ifndef STEX_STEX_H
#define STEX_STEX_H

#include <stddef.h>
#include <stdint.h>

/* STEX_API marks the exported functions (the only symbols libstex exports). */
#if defined(_WIN32)
#if defined(STEX_BUILDING_LIBRARY)
#define STEX_API __declspec(dllexport)
#else
#define STEX_API __declspec(dllimport)
#endif
#elif defined(__GNUC__) || defined(__clang__)
#define STEX_API __attribute__((visibility("default")))
#else
#define STEX_API
#endif

#ifdef __cplusplus
extern "C" {
#endif

/* The ABI this header describes; stex_abi_version() returns the library's. They must be equal. */
#define STEX_ABI_VERSION 0

/* OpenCL object types (OpenCL's cl_context is `struct _cl_context*`, and so on). */
struct _cl_context;
struct _cl_device_id;
struct _cl_command_queue;
struct _cl_mem;

/* ------------------------------------------------------------------------------------------------------
 * Status codes. Except STEX_INVALID_ARGUMENT, STEX_CANCELLED and STEX_UNAVAILABLE, the values equal the exit codes of the
 * `stex` command-line tool for the same kind of error (README "Exit codes"). STEX_INVALID_ARGUMENT is API
 * misuse detected at the boundary (a NULL handle or pointer, a struct_size below the first version's, an
 * unknown enum value, a non-zero reserved field, a row stride too small or not a multiple of 4, a cl_mem of
 * another context or too small); STEX_USAGE is a value outside its documented range.
 */
typedef enum stex_status {
  STEX_OK = 0,
  STEX_INTERNAL = 1, /* a bug or an unexpected condition (please report it with stex_last_error()) */
  STEX_USAGE = 2,    /* a parameter value outside its documented range (mni, scale, region, position) */
  STEX_INPUT = 3,    /* missing, unreadable, corrupt, foreign or unsupported input (file or pixels) */
  STEX_DEVICE = 4,   /* no OpenCL platform/device, no device matches the spec, kernel build failure */
  STEX_LIMIT = 5,    /* a size or resource limit: pixel budget, device allocation, host memory */
  STEX_OUTPUT = 6,   /* a file cannot be written */
  STEX_INVALID_ARGUMENT = 7, /* API misuse: NULL, struct_size, enum value, stride, foreign buffer */
  STEX_CANCELLED = 8,        /* the progress callback returned non-zero */
  STEX_UNAVAILABLE = 9,      /* an optional part of stex is not installed: the analysis library libstex_analysis.so */
  STEX_RETRYABLE = 75, /* a transient device failure (out of resources, device lost): may succeed on retry */
  STEX_INTERRUPTED = 130 /* stopped by a signal (not raised by the functions of this header today) */
} stex_status;

/* The name of a status ("STEX_OK", "STEX_USAGE", ...), or "STEX_UNKNOWN_STATUS". Static storage. */
STEX_API const char* stex_status_name(stex_status status);

/* The outcome of the most recent call on the calling thread of a function that returns stex_status (or of
 * a destroy function): its error message if it failed ("stex_render: --mni must be in (0, 10000], got -1"),
 * "" if it succeeded. stex_last_error, stex_status_name and the version functions do not change it. The
 * text stays valid until the next such call on this thread. Never NULL. */
STEX_API const char* stex_last_error(void);

/* Library version ("0.1.0") and ABI version (compare with STEX_ABI_VERSION). Static storage. */
STEX_API const char* stex_version_string(void);
STEX_API int stex_abi_version(void);

/* ------------------------------------------------------------------------------------------------------
 * Contexts: an OpenCL device, context and in-order command queue, plus compiled kernels and the device
 * copies of recently used models (a few; evicted least recently used).
 */
typedef struct stex_context stex_context;

/* Creates a context that owns its OpenCL objects. `device_spec`: NULL or "" for the default device (the
 * STEX_DEVICE environment variable is NOT consulted: the application decides), "cpu", "gpu", a decimal
 * index into the list of all devices of all platforms, or a case-insensitive substring of a device or
 * platform name. Errors: STEX_DEVICE (no platform, no match: the message lists the devices). */
STEX_API stex_status stex_context_create(const char* device_spec, stex_context** out);

/* Creates a context on the caller's OpenCL objects (borrowed). stex retains the three objects and releases
 * them in stex_context_destroy; it never creates other contexts or queues. `queue` must be an in-order
 * queue of `device` in `context` (profiling need not be enabled). stex enqueues its work on `queue` and
 * waits for it before returning, so commands the caller enqueued earlier on the same queue complete first.
 * Errors: STEX_INVALID_ARGUMENT (NULL object), STEX_DEVICE / STEX_INTERNAL (OpenCL query failures). */
STEX_API stex_status stex_context_create_from_cl(struct _cl_context* context, struct _cl_device_id* device,
                                                 struct _cl_command_queue* queue, stex_context** out);

/* Releases the context (waits for its queued work). Models used with it stay valid. NULL is ignored. */
STEX_API void stex_context_destroy(stex_context* context);

/* The device's name. The string lives as long as the context. */
STEX_API stex_status stex_context_device_name(const stex_context* context, const char** name);

/* The context's OpenCL objects (not retained: valid while the context lives), e.g. to create the cl_mem
 * for stex_render_cl. Any output pointer may be NULL. */
STEX_API stex_status stex_context_cl_objects(const stex_context* context, struct _cl_context** cl_context_out,
                                             struct _cl_device_id** cl_device_out,
                                             struct _cl_command_queue** cl_queue_out);

/* ------------------------------------------------------------------------------------------------------
 * Models: a noise model of any kind stex renders. The analysis functions make texton noise models (S1:
 * Galerne, Leclaire, Moisan, "Texton noise", 2017); stex_model_load reads every kind. Immutable.
 */
typedef struct stex_model stex_model;

/* Analysis parameters (analysis/texton.h documents the algorithm). */
typedef struct stex_analysis_params {
  size_t struct_size;    /* sizeof(stex_analysis_params) as the caller knows it (set by the init function) */
  uint64_t seed;         /* seed of the random initialisation (default 0); same inputs + seed = same model */
  uint64_t pixel_budget; /* largest exemplar width x height accepted (default 2^26); checked before reading */
  int32_t support;       /* texton side s in exemplar pixels, 1..4096, at most the exemplar size (64) */
  int32_t iterations;    /* iterations of S1 Algorithm 1, >= 1 (50) */
  int32_t order;         /* 1: bilinear texton (S1, default); 0: nearest (S2's synthesis-oriented texton); 3, 5: cubic, quintic B-spline (S1 §10) */
  int32_t colour_correction; /* 1: colour covariance correction (S1 §4.3, default); 0: off */
  int32_t linear;   /* 0 (default): analyse the values as stored. 1: files: decode sRGB to linear light
                       first; pixels: the caller's pixels are linear light. The model records it. */
  int32_t reserved; /* must be 0 */
} stex_analysis_params;

/* Fills `params` with the defaults above for the first `struct_size` bytes (pass sizeof *params) and sets
 * params->struct_size; bytes beyond the fields this library knows are zeroed. Errors:
 * STEX_INVALID_ARGUMENT (NULL, struct_size below the first version's size). */
STEX_API stex_status stex_analysis_params_init(stex_analysis_params* params, size_t struct_size);

/* Reads a model file (.stex; docs/model-format.md) of any kind stex renders ("texton", "lrp", "gabor",
 * ...: the kinds of `stex info`; stex_model_kind tells which). The file is validated completely (checksum,
 * sizes, the kind's fields) before use. Every kind renders through stex_render and stex_render_cl; point
 * queries and surface noise need a texton model. Errors: STEX_INPUT (missing, truncated, corrupt, foreign,
 * newer format, a kind this library does not know). */
STEX_API stex_status stex_model_load(const char* path, stex_model** out);

/* The model's kind ("texton", "lrp", "gabor", ...; static storage for the life of the model). Models made
 * by the analysis functions are texton models. */
STEX_API stex_status stex_model_kind(const stex_model* model, const char** kind);

/* Writes a model file atomically (temp file beside `path`, fsync, rename): `path` is either the complete
 * new file or untouched. Errors: STEX_OUTPUT. */
STEX_API stex_status stex_model_save(const stex_model* model, const char* path);

/* Analyses an exemplar image file (PNG, JPEG, TIFF, EXR, ... through OpenImageIO; alpha is dropped).
 * `params` may be NULL (defaults). Runs on the host (FFTW); no context needed. The analysis lives in
 * libstex_analysis.so, which the first analysis call loads from the directory of libstex.so (else from the
 * library search path; $STEX_ANALYSIS_LIBRARY names the file to load instead): an application that only
 * loads and renders models never loads OpenImageIO or FFTW. Errors: STEX_INPUT (unreadable or unsupported
 * file, exemplar smaller than the support), STEX_LIMIT (pixel budget), STEX_USAGE (parameter out of range),
 * STEX_UNAVAILABLE (libstex_analysis.so is not installed or is from another build; the message says what
 * was tried). */
STEX_API stex_status stex_model_analyse_file(const char* path, const stex_analysis_params* params,
                                             stex_model** out);

/* Analyses an exemplar in caller memory: `pixels` are floats, interleaved (pixel (x, y) channel c at
 * byte offset y * row_stride_bytes + (x * channels + c) * 4), `channels` 1..4 (all are analysed: pass
 * colour without alpha), row_stride_bytes 0 = width * channels * 4. The pixels are read during the call
 * only. The model records the exemplar name "(memory)" and the SHA-256 of the packed pixel bytes.
 * Errors: as stex_model_analyse_file, STEX_INPUT for NaN/Inf pixels, STEX_INVALID_ARGUMENT for NULL
 * pixels, sizes < 1 or a stride below a row or not a multiple of 4. */
STEX_API stex_status stex_model_analyse_pixels(const float* pixels, int32_t width, int32_t height,
                                               int32_t channels, size_t row_stride_bytes,
                                               const stex_analysis_params* params, stex_model** out);

/* Releases a model. NULL is ignored. */
STEX_API void stex_model_destroy(stex_model* model);

/* Every kind fills channels, linear and mean; the texton fields (support .. variance_kept) are 0 for other
 * kinds. */
typedef struct stex_model_info {
  size_t struct_size; /* set by the caller: sizeof(stex_model_info) */
  int32_t channels;   /* values per pixel of every render and point query: 1..4 */
  int32_t support;    /* texton side s */
  int32_t order;      /* 1 bilinear, 0 nearest, 3 cubic, 5 quintic */
  int32_t linear;     /* 1: values are linear light (encode to sRGB for display); 0: as the exemplar */
  int32_t exemplar_width, exemplar_height;
  int32_t iterations;
  int32_t reserved;
  uint64_t analysis_seed;
  double rme;           /* relative model error of the texton (S2), before colour correction */
  double variance_kept; /* noise variance before colour correction / exemplar variance */
  float mean[4];        /* mean per channel (unused channels 0) */
} stex_model_info;

/* Copies the model's properties into `info`; only the first info->struct_size bytes are written (set
 * struct_size first), bytes beyond the fields this library knows are zeroed. Errors: STEX_INVALID_ARGUMENT.
 */
STEX_API stex_status stex_model_get_info(const stex_model* model, stex_model_info* info);

/* ------------------------------------------------------------------------------------------------------
 * Rendering (S1 eq. 1-3; runtime/texton_params.h documents the parameters).
 *
 * A pixel's value depends only on (model, mni, cell_factor, scale, seed, its integer coordinates): never on
 * the region it is rendered in, the strategy, the context, the device type of a conformant device, the row
 * stride, or the thread. Tiles rendered separately therefore join seamlessly, bit for bit.
 */
typedef enum stex_strategy {
  STEX_STRATEGY_AUTO = 0,  /* splat on CPU devices, else gather (stex_render: the local-memory gather on GPUs) */
  STEX_STRATEGY_SPLAT = 1, /* blocks of pixels accumulate the impulses that reach them */
  STEX_STRATEGY_GATHER = 2 /* one work-item per pixel walks the cells within reach */
} stex_strategy;

/* Filtering of minified views (scale < 1; docs/filtering.md). Changes the output, unlike the strategy. */
typedef enum stex_filter {
  STEX_FILTER_AUTO = 0, /* filtered when the model filters and scale < 1 (texton order 1: S1 §5's MIP and
                           probes; gabor: each kernel convolved with the footprint; lrp: each cosine faded) */
  STEX_FILTER_ON = 1,   /* filtered at any scale; STEX_USAGE for a model that does not filter */
  STEX_FILTER_OFF = 2   /* point-sampled: minified views alias */
} stex_filter;

typedef struct stex_render_params {
  size_t struct_size; /* sizeof(stex_render_params) as the caller knows it (set by the init function) */
  double mni;         /* mean number of impacts per point, (0, 10000] (default 30) */
  double cell_factor; /* cell side of the impulse grid as a fraction of the texton size, [0.1, 2] (0.6);
                         changes the realisation, not the statistics */
  double scale;       /* output pixels per exemplar pixel, [1/1024, 1024] (1) */
  uint64_t seed;      /* the realisation (0) */
  int32_t strategy;   /* stex_strategy (AUTO); outputs never depend on it; ignored by point queries */
  int32_t filter;     /* stex_filter (AUTO); ignored by point queries. Was `reserved` (must be 0) before
                         1.x: 0 is AUTO, so such callers get filtered minified views */
} stex_render_params;

/* Fills `params` with the defaults above (see stex_analysis_params_init). */
STEX_API stex_status stex_render_params_init(stex_render_params* params, size_t struct_size);

/* Progress and cancellation. Called on the calling thread with the fraction done: 0 before the first chunk,
 * then after each chunk of rows, finally 1. Non-decreasing. Return 0 to continue, non-zero to cancel: the
 * render function then returns STEX_CANCELLED as soon as the callback returns (also when it cancels at 1)
 * and the output's content is unspecified (some rows may have been written, others not). */
typedef int (*stex_progress_fn)(double fraction, void* user);

/* Renders output pixels [x, x + width) x [y, y + height) into caller memory: pixel (i, j) of the region
 * (0 <= i < width, 0 <= j < height), channel c, is the float at byte offset
 *   j * row_stride_bytes + (i * channels + c) * 4      of `out`
 * (interleaved; channels from stex_model_get_info). row_stride_bytes 0 = width * channels * 4; otherwise
 * at least that and a multiple of 4; the bytes between rows are not touched. `params` NULL = defaults.
 * `progress` may be NULL. Blocking: returns when `out` is complete.
 * Errors: STEX_INVALID_ARGUMENT, STEX_USAGE (parameters, width or height < 1, |x| + width or |y| + height
 * >= 2^46), STEX_LIMIT, STEX_DEVICE, STEX_RETRYABLE, STEX_CANCELLED. */
STEX_API stex_status stex_render(stex_context* context, const stex_model* model,
                                 const stex_render_params* params, int64_t x, int64_t y, int32_t width,
                                 int32_t height, float* out, size_t row_stride_bytes,
                                 stex_progress_fn progress, void* user);

/* As stex_render, into an OpenCL buffer of the context's cl_context: pixel (i, j) channel c is the float at
 * byte offset  offset_bytes + j * row_stride_bytes + (i * channels + c) * 4  of `buffer` (the same
 * interleaved layout; row_stride_bytes 0 = packed; offset and stride multiples of 4). The buffer must be
 * writable by the device and large enough (checked with clGetMemObjectInfo). Enqueued on the context's
 * queue; the function returns after the writes completed. With the gather strategy (AUTO on GPUs) the
 * pixels are written by the device directly; with splat (AUTO on CPU devices, where device memory is host
 * memory) they are rendered to host memory and written with clEnqueueWriteBufferRect.
 * Errors: as stex_render; STEX_INVALID_ARGUMENT for a buffer of another context or too small. */
STEX_API stex_status stex_render_cl(stex_context* context, const stex_model* model,
                                    const stex_render_params* params, int64_t x, int64_t y, int32_t width,
                                    int32_t height, struct _cl_mem* buffer, size_t offset_bytes,
                                    size_t row_stride_bytes, stex_progress_fn progress, void* user);

/* Point queries: evaluates the texture at `count` positions on the context's device.
 * xy: 2 * count doubles, interleaved (x0, y0, x1, y1, ...), in output-pixel coordinates (the same frame as
 * stex_render: pixel (i, j) covers [i, i + 1) x [j, j + 1)). out: count * channels floats, point k channel c
 * at out[k * channels + c]. Each position is mapped to stex's fixed-point grid of 2^-16 output pixel as
 * X = round(x * 65536) (halfway cases away from zero), so the pixel centre (i + 0.5, j + 0.5) evaluates
 * exactly what stex_render writes for pixel (i, j), bit for bit; positions closer than 2^-17 pixel to each
 * other may give the same value. The texture is continuous (order 1) or piecewise constant at the texton
 * texel scale (order 0). `params` NULL = defaults; its strategy is ignored. count 0 is allowed.
 * Errors: STEX_INVALID_ARGUMENT (NULL arrays with count > 0), STEX_USAGE (a non-finite position or one with
 * |coordinate| >= 2^46: the message names its index), STEX_LIMIT, STEX_DEVICE, STEX_RETRYABLE, STEX_INPUT
 * (a model of another kind than texton). */
STEX_API stex_status stex_eval_points(stex_context* context, const stex_model* model,
                                      const stex_render_params* params, size_t count, const double* xy,
                                      float* out);

/* ------------------------------------------------------------------------------------------------------
 * Surface noise (S1 §6, Proposition 3; runtime/surface.h documents the parameters): texton noise evaluated
 * at points of a surface in 3-D, without a parameterisation. A point is a world position y with an
 * orthonormal frame (u1, u2, u3), u3 the surface normal; its value g^s(y) has the mean, the variance and, in
 * the tangent plane, the covariance of the model's plane noise, for any frame. The frame orients the texton
 * in the tangent plane: for a seamless texture it must vary continuously over the surface (e.g. interpolated
 * vertex normals and tangents). Texton models of order 0 or 1 only.
 */
typedef struct stex_surface_eval_params {
  size_t struct_size; /* sizeof(stex_surface_eval_params) as the caller knows it (set by the init function) */
  double mni;         /* mean number of impacts lambda r^3 (Proposition 3), (0, 10000] (default 60) */
  double cell_factor; /* cell side of the 3-D impulse grid as a fraction of the texton size, [0.1, 2] (0.6) */
  double texel;       /* world units per exemplar pixel: the texture's scale on the surface, [1e-9, 1e9] (1) */
  uint64_t seed;      /* the realisation (0) */
  int32_t reserved[2]; /* must be 0 */
} stex_surface_eval_params;

/* Fills `params` with the defaults above (see stex_analysis_params_init). */
STEX_API stex_status stex_surface_eval_params_init(stex_surface_eval_params* params, size_t struct_size);

/* Surface point queries: evaluates surface noise at `count` points on the context's device.
 * positions: 3 * count doubles (x0, y0, z0, x1, ...), world units; each is rounded to float before the
 *   evaluation (which runs in float texton units: |coordinate| / texel must be below 2^22).
 * normals: 3 * count doubles, u3 of each frame; any non-zero length (normalised).
 * tangents: NULL, or 3 * count doubles giving u1's direction: made orthogonal to the normal (Gram-Schmidt)
 *   and normalised. NULL, or a tangent parallel to its normal: u1 is the world X axis projected on the
 *   tangent plane (continuous over a surface except where the normal is parallel to X). u2 = u3 x u1.
 * out: count * channels floats, point k channel c at out[k * channels + c].
 * A point's value depends only on (model, mni, cell_factor, texel, seed, its float position and frame):
 * not on `count`, the other points, the batching, the context, the device type of a conformant device or
 * the thread. It equals stex's C++ reference (runtime/surface.h SurfaceReference) bit for bit.
 * `params` NULL = defaults. count 0 is allowed. Every point is checked before any device work.
 * Errors: STEX_INVALID_ARGUMENT (NULL arrays with count > 0, a non-zero reserved field), STEX_USAGE (a
 * parameter out of range; a non-finite or too distant position, a zero or non-finite normal, a non-finite
 * tangent: the message names the point's index), STEX_INPUT (a model of another kind than texton, or of
 * order 3 or 5), STEX_LIMIT, STEX_DEVICE, STEX_RETRYABLE. */
STEX_API stex_status stex_eval_surface_points(stex_context* context, const stex_model* model,
                                              const stex_surface_eval_params* params, size_t count,
                                              const double* positions, const double* normals,
                                              const double* tangents, float* out);

#ifdef __cplusplus
} /* extern "C" */
#endif

#endif /* STEX_STEX_H */
