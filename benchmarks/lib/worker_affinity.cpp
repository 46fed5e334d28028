// Worker threads pinned one per CPU for benchmark runs. See worker_affinity.h.
#include "benchmarks/lib/worker_affinity.h"

#include <omp.h>

#include <cstdlib>
#include <cstring>
#include <string>

#ifdef __linux__
#include <dirent.h>
#include <pthread.h>
#include <sched.h>
#include <sys/types.h>
#include <unistd.h>
#endif

namespace stex::bench {

namespace {

#ifdef __linux__
// The process's CPU set when pin_pocl_workers ran (before any thread pinned itself).
bool g_have_initial = false;
cpu_set_t g_initial;

const cpu_set_t& initial_set() {
  if (!g_have_initial) {
    CPU_ZERO(&g_initial);
    if (sched_getaffinity(0, sizeof(g_initial), &g_initial) == 0) g_have_initial = true;
  }
  return g_initial;
}

// Online CPUs 0..n-1 all in the initial set: n, else 0.
int full_prefix() {
  const long n = sysconf(_SC_NPROCESSORS_ONLN);
  if (n < 1 || n > CPU_SETSIZE) return 0;
  const cpu_set_t& s = initial_set();
  if (!g_have_initial) return 0;
  for (long c = 0; c < n; ++c)
    if (!CPU_ISSET(int(c), &s)) return 0;
  return int(n);
}
#endif

}  // namespace

WorkerAffinity pin_pocl_workers(bool enable) {
  WorkerAffinity a;
#ifdef __linux__
  (void)initial_set();
#endif
  if (const char* env = std::getenv("POCL_AFFINITY")) {
    a.setting = env;
    a.source = "environment";
    return a;
  }
  a.source = "not set";
  if (!enable) {
    a.note = "--no-pin";
    return a;
  }
#ifdef __linux__
  const int n = full_prefix();
  if (n == 0) {
    a.note = "the process may not run on every online CPU (a CPU set): PoCL would pin a worker outside it";
    return a;
  }
  if (n < 2) {
    a.note = "one CPU";
    return a;
  }
  if (const char* max = std::getenv("POCL_MAX_PTHREAD_COUNT")) {
    char* end = nullptr;
    const long m = std::strtol(max, &end, 10);
    if (end == max || *end != '\0' || m > n) {
      a.note = std::string("POCL_MAX_PTHREAD_COUNT=") + max + " is not a worker count <= the " +
               std::to_string(n) + " online CPUs";
      return a;
    }
  }
  if (setenv("POCL_AFFINITY", "1", 0) != 0) {
    a.note = "setenv failed";
    return a;
  }
  a.setting = "1";
  a.source = "stex bench";
#else
  a.note = "not Linux";
#endif
  return a;
}

int count_pinned_threads() {
#ifdef __linux__
  const cpu_set_t& s = initial_set();
  if (!g_have_initial || CPU_COUNT(&s) < 2) return -1;
  DIR* d = opendir("/proc/self/task");
  if (!d) return -1;
  int pinned = 0;
  while (const dirent* e = readdir(d)) {
    if (e->d_name[0] < '0' || e->d_name[0] > '9') continue;
    const pid_t tid = pid_t(std::strtol(e->d_name, nullptr, 10));
    cpu_set_t t;
    CPU_ZERO(&t);
    if (sched_getaffinity(tid, sizeof(t), &t) == 0 && CPU_COUNT(&t) == 1) ++pinned;
  }
  closedir(d);
  return pinned;
#else
  return -1;
#endif
}

void pin_openmp_threads(WorkerAffinity& a) {
#ifdef __linux__
  if (a.setting != "1") return;
  const int n = full_prefix();
  if (n < 2) return;
  int ok = 0, want = 0;
#pragma omp parallel reduction(+ : ok, want)
  {
    const int t = omp_get_thread_num();
    if (t > 0 && t < n) {
      ++want;
      cpu_set_t s;
      CPU_ZERO(&s);
      CPU_SET(t, &s);
      if (pthread_setaffinity_np(pthread_self(), sizeof(s), &s) == 0) ++ok;
    }
  }
  a.openmp_pinned = want > 0 && ok == want;
#else
  (void)a;
#endif
}

ScopedPinToCpu0::ScopedPinToCpu0(bool enable) {
#ifdef __linux__
  static_assert(sizeof(cpu_set_t) <= sizeof(saved_), "cpu_set_t does not fit");
  if (!enable) return;
  cpu_set_t old;
  CPU_ZERO(&old);
  if (pthread_getaffinity_np(pthread_self(), sizeof(old), &old) != 0 || !CPU_ISSET(0, &old)) return;
  cpu_set_t one;
  CPU_ZERO(&one);
  CPU_SET(0, &one);
  if (pthread_setaffinity_np(pthread_self(), sizeof(one), &one) != 0) return;
  std::memcpy(saved_, &old, sizeof(old));
  active_ = true;
#else
  (void)enable;
#endif
}

ScopedPinToCpu0::~ScopedPinToCpu0() {
#ifdef __linux__
  if (!active_) return;
  cpu_set_t old;
  std::memcpy(&old, saved_, sizeof(old));
  pthread_setaffinity_np(pthread_self(), sizeof(old), &old);
#endif
}

std::string describe(const WorkerAffinity& a) {
  std::string s = a.setting.empty() ? std::string("POCL_AFFINITY unset") : "POCL_AFFINITY=" + a.setting;
  s += " (";
  if (a.source == "stex bench") {
    s += "set by stex bench: PoCL worker i on CPU i";
  } else if (a.source == "environment") {
    s += "from the environment";
  } else {
    s += "not set" + (a.note.empty() ? std::string() : ": " + a.note);
  }
  if (a.pinned_threads >= 0) s += "; " + std::to_string(a.pinned_threads) + " threads pinned to one CPU";
  if (a.openmp_pinned) s += "; OpenMP pool pinned";
  return s + ")";
}

}  // namespace stex::bench
