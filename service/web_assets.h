// The viewer's files (service/web/), embedded at build time by cmake/embed_web.cmake like the kernel
// sources, so `stex serve` is one self-contained binary.
#pragma once
#include <cstddef>

namespace stex::service {
struct WebAsset {
  const char* name;  // path relative to service/web/ ("index.html")
  const char* text;
};
const WebAsset* web_assets(std::size_t* count);
}  // namespace stex::service
