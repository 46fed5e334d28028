// Constants of the host code's double-precision maths (the kernels' float constants live in kernels/shared).
#pragma once

namespace stex {

inline constexpr double k_pi = 3.14159265358979323846;

}  // namespace stex
