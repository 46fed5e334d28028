// Moisan's periodic + smooth decomposition (L. Moisan, "Periodic plus smooth image decomposition", JMIV
// 2011), the preprocess of S1 Algorithm 1 (§4.2: "if the input image u is not strictly periodic it is
// replaced by its periodic component"). u = p + s where p is periodic (its periodic Laplacian equals the
// Laplacian of u without wrap-around terms) with mean(p) = mean(u), and s is smooth (harmonic inside the
// domain, mean 0). Computed in the DFT domain: s^ = v^ / (2 cos(2 pi q/W) + 2 cos(2 pi r/H) - 4), s^(0,0) =
// 0, where v is the boundary image of wrap-around jumps.
#pragma once
#include <vector>

namespace stex {

// One channel, width x height row-major. Returns p; writes s if `smooth` is not null.
std::vector<double> periodic_component(int width, int height, const std::vector<double>& u,
                                       std::vector<double>* smooth = nullptr);

// The boundary image v of the decomposition: v = Laplacian_periodic(u) - Laplacian_free(u), non-zero only
// on the border (exposed for tests).
std::vector<double> periodic_boundary_image(int width, int height, const std::vector<double>& u);

// 5-point Laplacians: with wrap-around neighbours, and "free" (neighbours outside the domain omitted).
std::vector<double> laplacian_periodic(int width, int height, const std::vector<double>& u);
std::vector<double> laplacian_free(int width, int height, const std::vector<double>& u);

}  // namespace stex
