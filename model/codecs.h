// One codec per model kind: to_container(model) and <kind>_from_container(container, what). to_container
// validates the model first (Error(Usage) for an inconsistent model); <kind>_from_container reads every field
// with the readers of model/fields.h and validates the result (Error(Input) naming the field and `what`, the
// source), and refuses another kind by name. The file layout of each kind: docs/model-format.md.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "model/container.h"
#include "runtime/cs_hist.h"
#include "runtime/cs_rpn.h"
#include "runtime/cs_spot.h"
#include "runtime/gabor_params.h"
#include "runtime/lrp_model.h"
#include "runtime/mix_model.h"
#include "runtime/model.h"
#include "runtime/tb.h"

namespace stex {

// texton
ModelContainer to_container(const TextonModel& model);
TextonModel texton_from_container(const ModelContainer& model, const std::string& what = "model");
// Texton files: serialised (validating first) and parsed (every field checked; Error(Input) naming it).
std::vector<std::uint8_t> encode_model(const TextonModel& model);
TextonModel decode_model(const std::uint8_t* data, std::size_t size, const std::string& what = "model");
// Atomic (temp file beside the target + fsync + rename); Error(Output) on failure.
void save_model(const TextonModel& model, const std::string& path);
// The header's sizes are checked against the file length before the rest is read (Error(Input)).
TextonModel load_model(const std::string& path);

// lrp
ModelContainer to_container(const LrpModel& model);
LrpModel lrp_from_container(const ModelContainer& container, const std::string& what = "model");

// gabor
ModelContainer to_container(const GaborModel& model);
GaborModel gabor_from_container(const ModelContainer& model, const std::string& what = "model");

// mix
ModelContainer to_container(const MixModel& model);
MixModel mix_from_container(const ModelContainer& model, const std::string& what = "model");

// cs-spot, with the extra metadata its file carries (not needed to render: provenance and the estimate's
// quality).
struct CsModelInfo {
  std::string exemplar_name;
  bool linear = false;
  bool estimated = false;
  double d = -1.0, confidence = -1.0;  // < 0: not computed
  int border = 0;
};
ModelContainer to_container(const CsSpotModel& model, const CsModelInfo& info = {});
CsSpotModel cs_spot_from_container(const ModelContainer& model, const std::string& what = "model");

// tb and cs-tb (one codec: the kind says whether the model has periods)
ModelContainer to_container(const TbModel& model);
TbModel tb_from_container(const ModelContainer& model, const std::string& what = "model");

// cs-rpn
ModelContainer to_container(const CsRpnModel& model);
CsRpnModel cs_rpn_from_container(const ModelContainer& model, const std::string& what = "model");

// The histogram-transfer table that cs-spot and cs-tb files may carry: metadata "histogram": {"mode", "delta",
// "bins": [m0, m1], "q", "pca"} (absent for mode none: files written before the transfer existed load as mode
// none), the quantiles (then the basis if "pca") appended to the payload. The reader takes them off the end
// of `c`'s payload, which it shortens; Error(Input) for a malformed field or a payload too short.
void cs_hist_to_container(const CsHistTable& t, ModelContainer& c);
CsHistTable cs_hist_from_container(ModelContainer& c, int channels, const std::string& what);

}  // namespace stex
