// server_process.h: a real `cenote-server` process for end-to-end tests and the server benchmark:
// started on loopback with port 0 (the server picks a free port and writes it to --port-file) in
// a temporary directory of its own (port file, token file, snapshots, the server's log), stopped
// with SIGTERM when the object goes.
// Threads: one owner.
#pragma once

#include <sys/types.h>

#include <string>
#include <vector>

namespace cenote::client::test {

struct ServerProcessOptions {
  std::string token = {};               // non-empty: written to a file passed as --token-file
  std::string listen = "127.0.0.1:0";   // --listen; target() is loopback at the bound port
  std::vector<std::string> extra_args;  // appended to the command line (e.g. --config F)
  double start_timeout_s = 60.0;        // until the port file appears
};

class ServerProcess {
 public:
  // Starts `binary` and waits until it accepts calls.
  // @throws std::runtime_error when it cannot start, exits, or does not listen in time (the message
  //   carries the end of its log).
  ServerProcess(const std::string& binary, const ServerProcessOptions& options = {});
  ~ServerProcess();  // stop(), then removes the directory
  ServerProcess(const ServerProcess&) = delete;
  ServerProcess& operator=(const ServerProcess&) = delete;

  // "127.0.0.1:<port>"
  std::string target() const { return "127.0.0.1:" + std::to_string(port_); }
  int port() const { return port_; }
  pid_t pid() const { return pid_; }
  const std::string& directory() const { return dir_; }
  std::string snapshotDirectory() const { return dir_ + "/snapshots"; }
  // SIGTERM and wait (SIGKILL after timeout_s). @return the exit status (128 + signal if killed),
  // or the status already collected.
  int stop(double timeout_s = 30.0);
  // The server's stdout and stderr so far.
  std::string log() const;

 private:
  std::string dir_;
  pid_t pid_ = -1;
  int port_ = 0;
  int exit_status_ = -1;
};

}  // namespace cenote::client::test
