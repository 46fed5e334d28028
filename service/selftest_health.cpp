// The self-test report of /api/health (selftest_health.h).
#include "service/selftest_health.h"

#include <string>
#include <vector>

#include "runtime/selftest.h"

namespace stex::service {

nlohmann::json selftest_health(const DeviceInfo& device) {
  const std::vector<SelftestResult> seen = selftest_seen(device);
  std::vector<SelftestRow> rows = selftest_rows(device);
  for (const SelftestResult& r : seen) {
    bool listed = false;
    for (const SelftestRow& row : rows) listed = listed || row == r.row;
    if (!listed) rows.push_back(r.row);
  }
  const SelftestKey key = selftest_key(device);
  nlohmann::json list = nlohmann::json::array();
  int passed = 0, failed = 0, untested = 0;
  for (const SelftestRow& row : rows) {
    nlohmann::json e{{"kind", row.kind}, {"path", row.path}, {"state", "untested"}, {"source", ""}};
    const SelftestResult* found = nullptr;
    for (const SelftestResult& r : seen)
      if (r.row == row) found = &r;
    std::optional<SelftestResult> cached;
    if (!found && (cached = read_selftest_cache(key, row))) found = &*cached;
    if (found) {
      e["state"] = found->pass ? "pass" : "fail";
      e["source"] = cached ? "cache" : "this process";
      e["expected"] = found->expected;
      e["actual"] = found->actual;
      e["error"] = found->error;
    }
    if (found && !found->refused.empty()) e["state"] = "refused";
    (found ? (found->pass || !found->refused.empty() ? passed : failed) : untested) += 1;
    list.push_back(e);
  }
  const char* status = failed ? "fail" : untested ? "partial" : "pass";
  return {{"status", status}, {"passed", passed},  {"failed", failed},
          {"untested", untested}, {"cache", selftest_cache_dir()}, {"rows", list}};
}

}  // namespace stex::service
