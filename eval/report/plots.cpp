#include "eval/report/plots.h"

#include <unistd.h>

#include <array>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "common/error.h"

namespace cenote::eval {
namespace {

namespace fs = std::filesystem;

std::string shellQuote(const std::string& text) {
  std::string quoted = "'";
  for (char c : text) quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return quoted + "'";
}

std::string tail(const std::string& path, size_t max_chars) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  std::string s = text.str();
  return s.size() > max_chars ? "..." + s.substr(s.size() - max_chars) : s;
}

}  // namespace

std::vector<std::string> writePlots(const std::string& json_path, const std::string& out_dir) {
  const char* env = std::getenv("CENOTE_PYTHON");
  const std::string python = env && *env ? env : "/usr/bin/python3";
  if (access(python.c_str(), X_OK) != 0) {
    throw Error("plots need " + python + " with matplotlib (Debian: apt-get install python3-matplotlib); not found");
  }
  std::error_code ec;
  fs::create_directories(out_dir, ec);
  if (!fs::is_directory(out_dir)) throw Error("--plot " + out_dir + ": cannot create directory");
  const fs::path work = fs::temp_directory_path() / ("cenote_plot_" + std::to_string(getpid()));
  fs::create_directories(work, ec);
  const std::string script = (work / "plot_eval.py").string();
  const std::string errors = (work / "stderr.txt").string();
  std::ofstream(script) << plotScript();
  const std::string command = shellQuote(python) + " " + shellQuote(script) + " " + shellQuote(json_path) + " " +
                              shellQuote(out_dir) + " 2>" + shellQuote(errors);
  std::vector<std::string> written;
  FILE* pipe = popen(command.c_str(), "r");
  if (!pipe) throw Error("cannot run " + python);
  std::array<char, 4096> line{};
  while (fgets(line.data(), static_cast<int>(line.size()), pipe)) {
    std::string path = line.data();
    while (!path.empty() && (path.back() == '\n' || path.back() == '\r')) path.pop_back();
    if (!path.empty()) written.push_back(path);
  }
  const int status = pclose(pipe);
  const std::string message = tail(errors, 1500);
  fs::remove_all(work, ec);
  if (status != 0) {
    if (message.find("No module named 'matplotlib'") != std::string::npos) {
      throw Error("plots need matplotlib for " + python + " (Debian: apt-get install python3-matplotlib)");
    }
    throw Error("plot script failed on " + json_path + ":\n" + message);
  }
  return written;
}

}  // namespace cenote::eval
