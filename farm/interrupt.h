// SIGINT/SIGTERM handling for farm runs: the handler only records the signal; the batch loop checks it at
// every tile boundary, stops there, lets the writers remove their temp files, and the process exits with
// ErrorKind::Interrupted (130). A scheduler's preemption (Slurm sends SIGTERM, then SIGKILL after its
// KillWait) therefore never leaves a partial file under an output name.
#pragma once

namespace stex::farm {

// Installs the handlers for its lifetime and restores the previous ones afterwards. Not nestable.
class InterruptGuard {
 public:
  InterruptGuard();
  ~InterruptGuard();
  InterruptGuard(const InterruptGuard&) = delete;
  InterruptGuard& operator=(const InterruptGuard&) = delete;
};

// The signal received since the last reset (SIGINT or SIGTERM), or 0.
int interrupt_signal();
// Clears the recorded signal (InterruptGuard's constructor does this too).
void reset_interrupt();
// Records `sig` as if it had been delivered (tests, embedding applications with their own handlers).
void request_interrupt(int sig);

}  // namespace stex::farm
