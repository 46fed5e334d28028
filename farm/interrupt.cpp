// SIGINT/SIGTERM flag (farm/interrupt.h). The handler is async-signal-safe: it stores one sig_atomic_t.
#include "farm/interrupt.h"

#include <csignal>

namespace stex::farm {

namespace {

volatile std::sig_atomic_t g_signal = 0;
struct sigaction g_old_int, g_old_term;

extern "C" void on_signal(int sig) { g_signal = sig; }

}  // namespace

InterruptGuard::InterruptGuard() {
  g_signal = 0;
  struct sigaction sa {};
  sa.sa_handler = on_signal;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = SA_RESTART;  // writes in progress must not fail with EINTR: the tile finishes first
  sigaction(SIGINT, &sa, &g_old_int);
  sigaction(SIGTERM, &sa, &g_old_term);
}

InterruptGuard::~InterruptGuard() {
  sigaction(SIGINT, &g_old_int, nullptr);
  sigaction(SIGTERM, &g_old_term, nullptr);
}

int interrupt_signal() { return g_signal; }
void reset_interrupt() { g_signal = 0; }
void request_interrupt(int sig) { g_signal = sig; }

}  // namespace stex::farm
