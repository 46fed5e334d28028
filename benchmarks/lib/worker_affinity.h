// Worker threads pinned one per CPU for benchmark runs (`stex bench`, the stex_bench binary).
//
// Why: on the 2-vCPU VMs this project is measured on, the guest kernel packs threads that wake together onto
// one vCPU (its command line has sched_vcpu_pack=15): two threads woken for a ~15 ms burst shared one CPU for
// the whole burst in 14 of 40 bursts, never when each was pinned to its own CPU (docs/benchmarks.md). PoCL's
// pthread workers are woken together for every kernel, so a frame ran either on two CPUs or, packed, at one
// worker's speed, frame by frame: the medians of tb and of the texton splat then depended on how many of each
// side's frames were packed. PoCL pins worker i to CPU i when POCL_AFFINITY=1 (read when the device is
// created); the OpenMP baseline's threads are pinned the same way (pin_openmp_threads) so that the comparison
// stays like for like.
//
// Pinning is only safe when the process may run on CPUs 0..N-1 (N online CPUs): PoCL aborts if a worker's CPU
// is outside the process's CPU set (a Slurm or cgroup cpuset), so it is then left unset, and said.
#pragma once
#include <string>

namespace stex::bench {

struct WorkerAffinity {
  std::string setting;      // POCL_AFFINITY as the device saw it ("1", "0", ... ; empty: unset)
  std::string source;       // "stex bench" (set here), "environment" (the user's), "not set"
  std::string note;         // why it was not set, when it was not
  int pinned_threads = -1;  // threads of this process bound to one CPU, counted after the device ran; -1: n/a
                            // (the process itself may run on one CPU only, or the count was not taken)
  bool openmp_pinned = false;  // pin_openmp_threads() pinned the OpenMP pool's threads
};

// Call before the process's first OpenCL call. enable: set POCL_AFFINITY=1 unless the environment has it (the
// user's value wins) and unless the process's CPU set does not hold CPUs 0..N-1, or POCL_MAX_PTHREAD_COUNT
// asks for more workers than N.
WorkerAffinity pin_pocl_workers(bool enable);

// Threads of this process whose CPU affinity is exactly one CPU while the process's initial CPU set (taken by
// pin_pocl_workers, else now) has more than one; -1 when that is not so or /proc/self/task cannot be read.
int count_pinned_threads();

// When `a` pinned PoCL's workers (setting "1"): pins the OpenMP pool's thread t > 0 to CPU t (the calling
// thread, OpenMP's thread 0, keeps its CPU set, so that threads it creates later inherit the full set) and
// records it in a.openmp_pinned. Call once, after pin_pocl_workers. ScopedPinToCpu0 pins the caller for a
// region (the OpenMP baseline's timed runs), restoring its set afterwards.
void pin_openmp_threads(WorkerAffinity& a);

class ScopedPinToCpu0 {
 public:
  explicit ScopedPinToCpu0(bool enable);
  ~ScopedPinToCpu0();
  ScopedPinToCpu0(const ScopedPinToCpu0&) = delete;
  ScopedPinToCpu0& operator=(const ScopedPinToCpu0&) = delete;

 private:
  bool active_ = false;
  unsigned char saved_[128] = {};  // a cpu_set_t (Linux); opaque here
};

// One line for the reports: "POCL_AFFINITY=1 (set by stex bench; 2 threads pinned, OpenMP pool pinned)" etc.
std::string describe(const WorkerAffinity& a);

}  // namespace stex::bench
