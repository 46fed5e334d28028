// Whether this test binary (and so the stex binary of the same tree) is built with AddressSanitizer
// (scripts/san-configure.sh). Under ASan a process's resident memory includes the shadow memory, the redzones
// and the 256 MiB free quarantine, so tests that bound stex's RSS report the figure there but only assert it
// in the normal build, where it measures stex (docs/hardening.md).
#pragma once

namespace stex::test {

#if defined(__SANITIZE_ADDRESS__)
inline constexpr bool k_under_asan = true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
inline constexpr bool k_under_asan = true;
#else
inline constexpr bool k_under_asan = false;
#endif
#else
inline constexpr bool k_under_asan = false;
#endif

}  // namespace stex::test
