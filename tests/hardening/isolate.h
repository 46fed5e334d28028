// Process isolation for the hardening tests: runs a batch of loads in a forked child with a time bound
// per input and per batch (alarm) and an address-space cap (RLIMIT_AS, which also covers allocations OpenEXR makes inside
// open(): docs/hardening.md), so a crash, a hang or a runaway allocation is reported with the input that
// caused it instead of killing the test binary. The child announces each input on a pipe before loading it;
// the parent therefore knows which input was in flight when the child died.
//
// The child is forked without exec: it inherits the parent's libraries' state but none of its threads.
// A test binary that uses this harness must not read or write an EXR in its own process (OpenEXR's global
// thread pool would be inherited without its workers, and the child's next EXR read would wait forever):
// read images inside a batch instead.
#pragma once
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace stex::test {

struct IsolatedLimits {
  unsigned seconds = 60;                           // time bound for the whole batch
  unsigned per_input_seconds = 20;                 // time bound for each input (alarm re-armed per input)
  std::uint64_t address_space = std::uint64_t(1) << 30;  // RLIMIT_AS (skipped under ASan: its shadow needs more)
};

// Outcome of one batch: `failures` lists "input <id>: <what>" for every contract violation the child
// reported (through `fail`), plus one entry for a child that died (signal, alarm, exit code) naming the
// input in flight.
struct BatchResult {
  std::vector<std::string> failures;
  int inputs_done = 0;
};

// False under AddressSanitizer, whose shadow memory does not fit under RLIMIT_AS: the cap is not set then.
bool memory_cap_active();

// Runs `body(id, fail)` for every id in `ids` inside one forked child. `fail(message)` records a contract
// violation for the current id. Any exception escaping `body` is a failure too.
BatchResult run_isolated_batch(const std::vector<std::uint64_t>& ids,
                               const std::function<void(std::uint64_t id,
                                                        const std::function<void(const std::string&)>& fail)>& body,
                               const IsolatedLimits& limits = {});

}  // namespace stex::test
