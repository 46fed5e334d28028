// libFuzzer target for the exemplar path (issue #12): each input goes through stex::fuzz::exemplar_one
// (fuzz/entry_points.h), the same function the regression replay test runs in the normal build.
#include <cstddef>
#include <cstdint>

#include "fuzz/entry_points.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  stex::fuzz::exemplar_one(data, size);
  return 0;
}
