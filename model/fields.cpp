#include "model/fields.h"

#include <cmath>

#include "core/error.h"

namespace stex {

using nlohmann::json;

namespace {
[[noreturn]] void bad_key(const std::string& what, const char* key, const std::string& msg) {
  bad_model_field(what, std::string("metadata field '") + key + "' " + msg);
}
}  // namespace

void bad_model_field(const std::string& what, const std::string& msg) {
  throw Error(ErrorKind::Input, "model '" + what + "': " + msg);
}

void model_expect_kind(const ModelContainer& c, const char* expected, const std::string& what) {
  if (c.kind != expected) {
    bad_model_field(what, "model kind '" + c.kind + "' is not a " + expected + " model (this needs kind '" + expected +
                              "')");
  }
}

const json& model_field(const json& j, const char* key, const std::string& what) {
  if (!j.is_object()) bad_key(what, key, "is missing (its parent is not an object)");
  const auto it = j.find(key);
  if (it == j.end()) bad_key(what, key, "is missing");
  return *it;
}

const json& model_object(const json& j, const char* key, const std::string& what) {
  const json& v = model_field(j, key, what);
  if (!v.is_object()) bad_key(what, key, "is not an object");
  return v;
}

double model_number(const json& j, const char* key, const std::string& what) {
  const json& v = model_field(j, key, what);
  if (!v.is_number()) bad_key(what, key, "is not a number");
  const double d = v.get<double>();
  if (!std::isfinite(d)) bad_key(what, key, "is not finite");
  return d;
}

long long model_integer(const json& j, const char* key, long long lo, long long hi, const std::string& what) {
  const json& v = model_field(j, key, what);
  if (!v.is_number_integer()) bad_key(what, key, "is not an integer");
  const bool above = v.is_number_unsigned() && v.get<unsigned long long>() > static_cast<unsigned long long>(hi);
  const long long x = above ? hi : v.get<long long>();
  if (above || x < lo || x > hi) {
    bad_key(what, key, "= " + v.dump() + " is out of range [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
  }
  return x;
}

int model_int(const json& j, const char* key, int lo, int hi, const std::string& what) {
  return int(model_integer(j, key, lo, hi, what));
}

std::uint64_t model_unsigned(const json& j, const char* key, const std::string& what) {
  const json& v = model_field(j, key, what);
  if (!v.is_number_unsigned() && !(v.is_number_integer() && v.get<long long>() >= 0))
    bad_key(what, key, "is not an unsigned integer");
  return v.get<std::uint64_t>();
}

std::string model_string(const json& j, const char* key, const std::string& what) {
  const json& v = model_field(j, key, what);
  if (!v.is_string()) bad_key(what, key, "is not a string");
  return v.get<std::string>();
}

bool model_bool(const json& j, const char* key, const std::string& what) {
  const json& v = model_field(j, key, what);
  if (!v.is_boolean()) bad_key(what, key, "is not a boolean");
  return v.get<bool>();
}

std::array<float, 4> model_means(const json& j, const char* key, int channels, const std::string& what) {
  const json& v = model_field(j, key, what);
  if (!v.is_array() || int(v.size()) != channels)
    bad_key(what, key, "is not an array of " + std::to_string(channels) + " numbers");
  std::array<float, 4> m{};
  for (int c = 0; c < channels; ++c) {
    const json& x = v[std::size_t(c)];
    if (!x.is_number() || !std::isfinite(x.get<double>()) || std::fabs(x.get<double>()) > 3.4e38)
      bad_key(what, key, "has a non-finite entry");
    m[std::size_t(c)] = float(x.get<double>());
  }
  return m;
}

ModelPeriods model_periods(const json& meta, const std::string& what) {
  const json& per = model_field(meta, "periods", what);
  if (!per.is_array() || per.size() != 2 || !per[0].is_array() || !per[1].is_array() || per[0].size() != 2 ||
      per[1].size() != 2)
    bad_model_field(what, "metadata field 'periods' must be [[t0x, t0y], [t1x, t1y]]");
  for (int i = 0; i < 2; ++i)
    for (int k = 0; k < 2; ++k)
      if (!per[i][k].is_number() || !std::isfinite(per[i][k].get<double>()))
        bad_model_field(what, "metadata field 'periods' has a non-numeric or non-finite entry");
  return {per[0][0].get<double>(), per[0][1].get<double>(), per[1][0].get<double>(), per[1][1].get<double>()};
}

json periods_json(double t0x, double t0y, double t1x, double t1y) {
  return json::array({json::array({t0x, t0y}), json::array({t1x, t1y})});
}

}  // namespace stex
