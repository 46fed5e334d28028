// The HTTP front of stex serve: cpp-httplib (Debian libcpp-httplib-dev) on loopback by default, a fixed
// pool of connection threads, every GET handed to Service::handle. SIGINT/SIGTERM stop it cleanly: the
// listener closes, in-flight requests finish, the device worker stops.
#pragma once
#include <functional>
#include <string>

#include "service/service.h"

namespace stex::service {

struct ServerOptions {
  std::string host = "127.0.0.1";
  int port = 8080;          // 0: any free port (printed, and written to port_file)
  int threads = 16;         // connection threads (each serves one keep-alive connection at a time)
  std::string port_file;    // when set: the bound port is written there (atomically) once listening
};

// Binds (Error(Usage) when the address cannot be bound), calls on_listening(port), serves until SIGINT or
// SIGTERM (or stop_server()), then returns the signal number (0 for stop_server()).
int run_server(Service& service, const ServerOptions& options, const std::function<void(int port)>& on_listening);
// Blocks SIGINT and SIGTERM in the calling thread and the threads it creates later; call it before creating
// the Service (its device worker and the OpenCL runtime's threads must not take the signals), so that
// run_server's sigwait receives them.
void block_stop_signals();
// Stops a running run_server from another thread (tests).
void stop_server();

}  // namespace stex::service
