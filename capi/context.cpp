// C API contexts (include/stex/stex.h "Contexts"): stex's own OpenCL context or the caller's borrowed one
// (runtime/context.h), the per-context cache of model device copies, and the C API's own kernels.
#include <CL/cl.h>

#include <string>

#include "capi/api_internal.h"
#include "runtime/cl_error.h"

namespace stex::capi {
namespace {

stex_context* new_context(std::unique_ptr<Context> ctx) {
  auto handle = std::make_unique<stex_context>();
  handle->device_name = ctx->info().name;
  handle->ctx = std::move(ctx);
  return handle.release();
}

bool same_params(const RenderParams& a, const RenderParams& b) {
  return a.mni == b.mni && a.cell_factor == b.cell_factor && a.seed == b.seed && a.scale == b.scale;
}

template <class T>
T queue_info(cl_command_queue queue, cl_command_queue_info what, const char* name) {
  T value{};
  cl_int err = clGetCommandQueueInfo(queue, what, sizeof value, &value, nullptr);
  if (err != CL_SUCCESS) throw OpenCLError("clGetCommandQueueInfo", err, std::string("querying ") + name);
  return value;
}

}  // namespace

ModelEntry& model_entry(stex_context& context, const stex_model& model) {
  auto& models = context.models;
  for (auto it = models.begin(); it != models.end(); ++it) {
    if (it->serial == model.serial) {
      models.splice(models.begin(), models, it);
      return models.front();
    }
  }
  ModelEntry entry;
  entry.serial = model.serial;
  if (model.texton)
    entry.renderer = std::make_unique<TextonRenderer>(*context.ctx, *model.texton);
  else
    entry.noise = model.loaded.make_renderer(*context.ctx);
  models.push_front(std::move(entry));
  while (models.size() > k_model_cache_size) models.pop_back();
  return models.front();
}

const TextonModel& texton_of(const stex_model& model, const char* what) {
  if (!model.texton)
    throw Error(ErrorKind::Input, std::string(what) + " need a texton model; this model is of kind '" +
                                      model.loaded.container.kind + "'");
  return *model.texton;
}

const TextonSetup& device_setup(stex_context& context, ModelEntry& entry, const TextonModel& model,
                                const RenderParams& params) {
  if (!entry.setup || !same_params(entry.setup_params, params)) {
    auto setup = std::make_unique<TextonSetup>(make_texton_setup(model, params));
    // alpha depends on the model only; the Poisson table on (mni, cell factor, scale).
    if (!entry.alpha.get())
      entry.alpha = Buffer<float>(*context.ctx, setup->alpha_padded, CL_MEM_READ_ONLY, "texton alpha");
    if (!entry.table.get() || !entry.setup || entry.setup->poisson_table != setup->poisson_table)
      entry.table =
          Buffer<std::uint32_t>(*context.ctx, setup->poisson_table, CL_MEM_READ_ONLY, "Poisson table");
    entry.setup = std::move(setup);
    entry.setup_params = params;
  }
  return *entry.setup;
}

void ensure_kernels(stex_context& context) {
  if (context.program) return;
  const std::string source = resolve_kernel_source("shared/texton.h") + device_kernel_source();
  auto program = std::make_unique<Program>(*context.ctx, source, "", "stex C API kernels");
  context.points_kernel = std::make_unique<Kernel>(*program, "stex_capi_points");
  context.region_kernel = std::make_unique<Kernel>(*program, "stex_capi_region");
  context.program = std::move(program);
}

}  // namespace stex::capi

using stex::capi::guard;
using stex::capi::invalid_argument;

extern "C" {

STEX_API stex_status stex_context_create(const char* device_spec, stex_context** out) {
  if (out) *out = nullptr;
  return guard("stex_context_create", [&] {
    if (!out) invalid_argument("out is NULL");
    *out = stex::capi::new_context(stex::Context::create(device_spec ? device_spec : ""));
  });
}

STEX_API stex_status stex_context_create_from_cl(struct _cl_context* context, struct _cl_device_id* device,
                                                 struct _cl_command_queue* queue, stex_context** out) {
  if (out) *out = nullptr;
  return guard("stex_context_create_from_cl", [&] {
    if (!out) invalid_argument("out is NULL");
    if (!context || !device || !queue)
      invalid_argument("the cl_context, cl_device_id and cl_command_queue must all be non-NULL");
    using stex::capi::queue_info;
    if (queue_info<cl_context>(queue, CL_QUEUE_CONTEXT, "CL_QUEUE_CONTEXT") != context)
      invalid_argument("the command queue does not belong to the given cl_context");
    if (queue_info<cl_device_id>(queue, CL_QUEUE_DEVICE, "CL_QUEUE_DEVICE") != device)
      invalid_argument("the command queue does not belong to the given cl_device_id");
    if (queue_info<cl_command_queue_properties>(queue, CL_QUEUE_PROPERTIES, "CL_QUEUE_PROPERTIES") &
        CL_QUEUE_OUT_OF_ORDER_EXEC_MODE_ENABLE)
      invalid_argument("the command queue is out-of-order; stex needs an in-order queue");
    *out = stex::capi::new_context(std::make_unique<stex::Context>(context, device, queue));
  });
}

STEX_API void stex_context_destroy(stex_context* context) {
  // Destructors of the OpenCL wrappers do not throw; the firewall still guards against the unexpected.
  guard("stex_context_destroy", [&] { delete context; });
}

STEX_API stex_status stex_context_device_name(const stex_context* context, const char** name) {
  if (name) *name = nullptr;
  return guard("stex_context_device_name", [&] {
    if (!context || !name) invalid_argument("context or name is NULL");
    *name = context->device_name.c_str();
  });
}

STEX_API stex_status stex_context_cl_objects(const stex_context* context, struct _cl_context** cl_context_out,
                                             struct _cl_device_id** cl_device_out,
                                             struct _cl_command_queue** cl_queue_out) {
  return guard("stex_context_cl_objects", [&] {
    if (!context) invalid_argument("context is NULL");
    if (cl_context_out) *cl_context_out = context->ctx->context();
    if (cl_device_out) *cl_device_out = context->ctx->device();
    if (cl_queue_out) *cl_queue_out = context->ctx->queue();
  });
}

}  // extern "C"
