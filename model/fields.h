// The field readers every codec reads its metadata with (model/codecs.h). Each one throws Error(Input)
// "model '<what>': metadata field '<key>' ..." naming the field and what is wrong with it: missing, wrong
// type, not finite, out of [lo, hi]. `what` names the source (a file name) in the message.
#pragma once
#include <array>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>

#include "core/error.h"
#include "model/container.h"

namespace stex {

[[noreturn]] void bad_model_field(const std::string& what, const std::string& msg);

// Refuses a container of another kind: "model kind '<kind>' is not a <expected> model".
void model_expect_kind(const ModelContainer& c, const char* expected, const std::string& what);

// The value at `key` of the object `j` (missing, or `j` not an object: Error(Input)).
const nlohmann::json& model_field(const nlohmann::json& j, const char* key, const std::string& what);
// The object at `key`.
const nlohmann::json& model_object(const nlohmann::json& j, const char* key, const std::string& what);
double model_number(const nlohmann::json& j, const char* key, const std::string& what);  // finite
long long model_integer(const nlohmann::json& j, const char* key, long long lo, long long hi, const std::string& what);
int model_int(const nlohmann::json& j, const char* key, int lo, int hi, const std::string& what);
std::uint64_t model_unsigned(const nlohmann::json& j, const char* key, const std::string& what);
std::string model_string(const nlohmann::json& j, const char* key, const std::string& what);
bool model_bool(const nlohmann::json& j, const char* key, const std::string& what);
// An array of `channels` finite float values (1..4 channels); the rest of the result is 0.
std::array<float, 4> model_means(const nlohmann::json& j, const char* key, int channels, const std::string& what);

// A lattice's two period vectors, stored as [[t0x, t0y], [t1x, t1y]] (cs-spot, cs-rpn, cs-tb).
struct ModelPeriods {
  double t0x = 0, t0y = 0, t1x = 0, t1y = 0;
};
ModelPeriods model_periods(const nlohmann::json& meta, const std::string& what);
// Reads the periods into a model with members t0x, t0y, t1x, t1y.
template <class M>
void model_periods_into(M& m, const nlohmann::json& meta, const std::string& what) {
  const ModelPeriods p = model_periods(meta, what);
  m.t0x = p.t0x;
  m.t0y = p.t0y;
  m.t1x = p.t1x;
  m.t1y = p.t1y;
}
nlohmann::json periods_json(double t0x, double t0y, double t1x, double t1y);

// A codec's to_container validates with the model's own check, whose Error becomes Error(Usage) there (the
// caller built an inconsistent model) and Error(Input) naming the source in <kind>_from_container.
template <class Check>
void validate_for_save(Check&& check) {
  try {
    check();
  } catch (const Error& e) {
    throw Error(ErrorKind::Usage, e.what());
  }
}
template <class Check>
void validate_loaded(Check&& check, const std::string& what) {
  try {
    check();
  } catch (const Error& e) {
    bad_model_field(what, e.what());
  }
}

}  // namespace stex
