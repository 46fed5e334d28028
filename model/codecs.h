// One codec per model kind, each in its own header model/<kind>_codec.h (this header includes them all):
// to_container(model) and <kind>_from_container(container, what). to_container validates the model first
// (Error(Usage) for an inconsistent model); <kind>_from_container reads every field with the readers of
// model/fields.h and validates the result (Error(Input) naming the field and `what`, the source), and refuses
// another kind by name. The file layout of each kind: docs/model-format.md.
#pragma once
#include "model/cs_hist_codec.h"
#include "model/cs_rpn_codec.h"
#include "model/cs_spot_codec.h"
#include "model/gabor_codec.h"
#include "model/lrp_codec.h"
#include "model/mix_codec.h"
#include "model/tb_codec.h"
#include "model/texton_codec.h"
