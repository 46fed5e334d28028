// cpp-httplib adapter and signal handling of stex serve (service/server.h).
#include "service/server.h"

#include <pthread.h>
#include <signal.h>
#include <sys/socket.h>

#include <atomic>
#include <cstdio>
#include <httplib.h>
#include <mutex>
#include <thread>

#include "core/atomic_file.h"
#include "core/error.h"

namespace stex::service {
namespace {

std::mutex g_mutex;
httplib::Server* g_server = nullptr;

}  // namespace

void block_stop_signals() {
  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, SIGINT);
  sigaddset(&set, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &set, nullptr);
}

void stop_server() {
  std::lock_guard<std::mutex> lock(g_mutex);
  if (g_server) g_server->stop();
}

int run_server(Service& service, const ServerOptions& options, const std::function<void(int)>& on_listening) {
  if (options.threads < 1 || options.threads > 1024) throw Error(ErrorKind::Usage, "--threads must be in [1, 1024]");
  if (options.port < 0 || options.port > 65535) throw Error(ErrorKind::Usage, "--port must be in [0, 65535]");
  httplib::Server server;
  const int threads = options.threads;
  server.new_task_queue = [threads] { return new httplib::ThreadPool(std::size_t(threads)); };
  // SO_REUSEADDR only: httplib's default SO_REUSEPORT would let a second server share a port in use.
  server.set_socket_options([](socket_t sock) {
    int yes = 1;
    setsockopt(sock, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof yes);
  });
  server.set_keep_alive_max_count(100);
  server.set_keep_alive_timeout(5);
  server.set_read_timeout(5);
  server.set_write_timeout(5);
  server.set_payload_max_length(1 << 16);  // GET only: no bodies
  server.Get(R"(/.*)", [&service](const httplib::Request& req, httplib::Response& res) {
    Request r;
    r.path = req.path;
    for (const auto& kv : req.params) r.query.emplace(kv.first, kv.second);
    Response out = service.handle(r);
    res.status = out.status;
    for (const auto& h : out.headers) res.set_header(h.first, h.second);
    res.set_content(std::move(out.body), out.content_type.c_str());
  });

  // Signals: blocked in every thread (the pool threads are created after this), taken by sigwait below.
  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, SIGINT);
  sigaddset(&set, SIGTERM);
  sigset_t old;
  pthread_sigmask(SIG_BLOCK, &set, &old);

  int port = options.port;
  if (port == 0) {
    port = server.bind_to_any_port(options.host);
    if (port < 0) port = -1;
  } else if (!server.bind_to_port(options.host, port)) {
    port = -1;
  }
  if (port <= 0) {
    pthread_sigmask(SIG_SETMASK, &old, nullptr);
    throw Error(ErrorKind::Usage, "cannot listen on " + options.host + ":" + std::to_string(options.port) +
                                      " (address in use or not local)");
  }
  if (!options.port_file.empty()) {
    const std::string text = std::to_string(port) + "\n";
    write_file_atomic(options.port_file, text.data(), text.size());
  }
  {
    std::lock_guard<std::mutex> lock(g_mutex);
    g_server = &server;
  }
  std::atomic<int> signal_seen{0};
  std::thread waiter([&] {
    int sig = 0;
    while (sigwait(&set, &sig) == 0) {
      if (sig == SIGINT || sig == SIGTERM) {
        signal_seen = sig;
        server.stop();
        return;
      }
    }
  });
  on_listening(port);
  server.listen_after_bind();
  {
    std::lock_guard<std::mutex> lock(g_mutex);
    g_server = nullptr;
  }
  const int sig = signal_seen.load();
  if (sig == 0) pthread_kill(waiter.native_handle(), SIGTERM);  // stop_server(): wake the waiter
  waiter.join();
  service.stop();
  pthread_sigmask(SIG_SETMASK, &old, nullptr);
  return sig;
}

}  // namespace stex::service
