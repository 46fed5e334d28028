// Kernel sources embedded at build time (cmake/embed_sources.cmake): kernels/*.cl and kernels/shared/*.h,
// named by their path relative to kernels/ ("texton_splat.cl", "shared/texton.h").
#pragma once
#include <cstddef>

namespace stex {
struct EmbeddedSource {
  const char* name;
  const char* text;
};
// The generated table (build/generated/embedded_kernels.cpp).
const EmbeddedSource* embedded_sources(std::size_t* count);
}  // namespace stex
