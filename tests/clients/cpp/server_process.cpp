// server_process.cpp: ServerProcess (fork/exec, port file, SIGTERM).
#include "tests/clients/cpp/server_process.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <thread>

namespace cenote::client::test {

namespace {
std::string readAll(const std::string& path) {
  std::ifstream in(path);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

// Exit status in the shell's convention.
int decodeStatus(int status) {
  if (WIFEXITED(status)) return WEXITSTATUS(status);
  if (WIFSIGNALED(status)) return 128 + WTERMSIG(status);
  return -1;
}
}  // namespace

ServerProcess::ServerProcess(const std::string& binary, const ServerProcessOptions& options) {
  std::string tmpl = (std::filesystem::temp_directory_path() / "cenote-server-XXXXXX").string();
  if (!mkdtemp(tmpl.data())) throw std::runtime_error("ServerProcess: cannot make a temporary directory");
  dir_ = tmpl;
  std::filesystem::create_directories(snapshotDirectory());
  const std::string port_file = dir_ + "/port";
  std::vector<std::string> args = {binary,    "--listen",       options.listen,     "--port-file",
                                   port_file, "--snapshot-dir", snapshotDirectory()};
  if (!options.token.empty()) {
    std::ofstream(dir_ + "/token") << options.token << "\n";
    args.push_back("--token-file");
    args.push_back(dir_ + "/token");
  }
  args.insert(args.end(), options.extra_args.begin(), options.extra_args.end());

  const std::string log_path = dir_ + "/server.log";
  pid_ = fork();
  if (pid_ < 0) throw std::runtime_error("ServerProcess: fork failed");
  if (pid_ == 0) {
    const int fd = open(log_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (fd >= 0) {
      dup2(fd, 1);
      dup2(fd, 2);
      close(fd);
    }
    std::vector<char*> argv;
    for (std::string& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    execv(argv[0], argv.data());
    _exit(127);
  }

  const auto give_up = std::chrono::steady_clock::now() + std::chrono::duration<double>(options.start_timeout_s);
  while (std::chrono::steady_clock::now() < give_up) {
    int status = 0;
    if (waitpid(pid_, &status, WNOHANG) == pid_) {
      exit_status_ = decodeStatus(status);
      const std::string tail = log();
      std::filesystem::remove_all(dir_);
      throw std::runtime_error("cenote-server exited with status " + std::to_string(exit_status_) +
                               " before listening: " + tail);
    }
    const std::string text = readAll(port_file);
    if (!text.empty() && text.back() == '\n') {
      port_ = std::atoi(text.c_str());
      if (port_ > 0) return;
    } else if (!text.empty()) {
      const int port = std::atoi(text.c_str());
      // Without a newline the file may still be being written; a full port number is enough
      // once it has stayed the same for one more poll.
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
      if (port > 0 && readAll(port_file) == text) {
        port_ = port;
        return;
      }
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  const std::string tail = log();
  stop(5.0);
  std::filesystem::remove_all(dir_);
  throw std::runtime_error("cenote-server did not write its port file within " + std::to_string(options.start_timeout_s) +
                           " s: " + tail);
}

ServerProcess::~ServerProcess() {
  stop();
  std::error_code ignored;
  std::filesystem::remove_all(dir_, ignored);
}

int ServerProcess::stop(double timeout_s) {
  if (exit_status_ >= 0 || pid_ <= 0) return exit_status_;
  kill(pid_, SIGTERM);
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  int status = 0;
  while (std::chrono::steady_clock::now() < give_up) {
    if (waitpid(pid_, &status, WNOHANG) == pid_) {
      exit_status_ = decodeStatus(status);
      return exit_status_;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  kill(pid_, SIGKILL);
  waitpid(pid_, &status, 0);
  exit_status_ = decodeStatus(status);
  return exit_status_;
}

std::string ServerProcess::log() const {
  std::string text = readAll(dir_ + "/server.log");
  return text.size() > 4000 ? text.substr(text.size() - 4000) : text;
}

}  // namespace cenote::client::test
