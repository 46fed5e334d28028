// Cyclostationary random-phase noise models (kind "cs-rpn", runtime/cs_rpn.h) from user spectra (S4 §4.2,
// Fig. 1 left and 4), and their codec (docs/model-format.md, docs/cyclostationary.md).
//
// A spectrum is given as LRP's continuous-spectrum specs (analysis/lrp.h lrp_analytic_psd: ring:F,W |
// bilobe:F,ANGLE,W | gauss:FX,FY,W[;...]) on a T x T grid, or as a PSD image (lrp_psd_from_image: square,
// power of two T, zero frequency at the centre). Its bins become the table of the model: the full-plane
// PSD is folded onto the half plane {f . d > 0} of its principal direction d (the leading eigenvector of
// sum P(f) f f^T, sign with d.x > 0, or d.y > 0 when d.x = 0), each kept bin weighing P(f) + P(-f); bins
// beyond 0.5 cycles per pixel are dropped. The fold keeps each lobe pair of a bi-lobe on one side, which
// phasor noise needs (its kernels are complex: f and -f differ); cos-based variants do not depend on it.
//
// The spectra file (JSON; `stex cs-rpn --spectra FILE`):
//   {
//     "grid": [K0, K1],                 // spectra along t0 and t1 (1..16 each); K0 K1 entries below
//     "size": T,                        // frequency grid of the analytic specs (16..1024, power of two; 64)
//     "spectra": [ SPEC, ... ]          // row-major: entry j K0 + i at phase (i / K0, j / K1)
//   }
// SPEC is a string (an analytic spec, variance 0.0225) or an object {"psd": "bilobe:...", "variance": V} or
// {"image": "PATH", "variance": V} (PATH relative to the file; its side must be T).
#pragma once
#include <string>

#include <nlohmann/json.hpp>

#include "analysis/lrp.h"
#include "model/codecs.h"
#include "runtime/cs_rpn.h"

namespace stex {

// One spectrum's table from a full-plane PSD (LrpSpectrum's psd, FFT order), with energy `variance`.
// Error(Usage) when no bin is left.
CsRpnSpectrum cs_rpn_spectrum(const LrpSpectrum& psd, double variance, const std::string& source = "");

// Fills model.k0, k1, spectra and bin (= 1 / T) from a spectra file's JSON (`base_dir` resolves image paths);
// the other fields of `model` (variant, periods, mean, bandwidth, spacing, cosines) are kept. Error(Usage)
// naming the problem (a bad spec, a missing field, a wrong count); Error(Input) for an unreadable image.
void cs_rpn_load_spectra(CsRpnModel& model, const nlohmann::json& spectra, const std::string& base_dir = ".");
// The same from a file; Error(Input) when it is missing or not JSON.
void cs_rpn_load_spectra_file(CsRpnModel& model, const std::string& path);


}  // namespace stex
