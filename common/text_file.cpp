#include "common/text_file.h"

#include <fstream>
#include <sstream>

#include "common/error.h"

namespace cenote {

std::string readFileBytes(const std::string& path, const std::string& what) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(what + " " + path + " cannot be read");
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

std::string readTokenFile(const std::string& path, const std::string& what) {
  std::ifstream in(path);
  if (!in) throw Error(what + " " + path + " cannot be read");
  std::string line;
  std::getline(in, line);
  const size_t first = line.find_first_not_of(" \t\r\n");
  const size_t last = line.find_last_not_of(" \t\r\n");
  if (first == std::string::npos) throw Error(what + " " + path + " holds no token on its first line");
  return line.substr(first, last - first + 1);
}

}  // namespace cenote
