// cli_input.cpp: parsing of cenote-cli's points and files.
#include "clients/cli/cli_input.h"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "common/text_parse.h"

namespace cenote::cli {

namespace {
// Parses exactly three numbers separated by `separators`; false otherwise.
bool parseThree(std::string text, const std::string& separators, Eigen::Vector3d& out) {
  for (char& c : text) {
    if (separators.find(c) != std::string::npos) c = ' ';
  }
  std::istringstream in(text);
  double v[3];
  for (double& x : v) {
    std::string word;
    if (!(in >> word)) return false;
    char* end = nullptr;
    x = std::strtod(word.c_str(), &end);
    if (end == word.c_str() || *end != '\0') return false;
  }
  std::string extra;
  if (in >> extra) return false;
  out = Eigen::Vector3d(v[0], v[1], v[2]);
  return true;
}
}  // namespace

Eigen::Vector3d parsePoint(const std::string& text, const std::string& what) {
  const std::optional<Eigen::Vector3d> p = text.find_first_of(" \t") == std::string::npos ? cenote::parsePoint(text)
                                                                                          : std::nullopt;
  if (!p) throw CliError(what + " '" + text + "': expected X,Y,Z (three numbers in metres, comma-separated)");
  return *p;
}

std::vector<Eigen::Vector3d> readPointsFile(const std::string& path) {
  std::ifstream file(path);
  if (!file) throw CliError("--points-file " + path + ": cannot open");
  std::vector<Eigen::Vector3d> points;
  std::string line;
  for (int number = 1; std::getline(file, line); ++number) {
    const size_t first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    Eigen::Vector3d p;
    if (!parseThree(line, " \t\r,", p)) {
      throw CliError("--points-file " + path + ":" + std::to_string(number) + ": expected 'x y z', got '" + line + "'");
    }
    points.push_back(p);
  }
  return points;
}

std::string formatNumber(double v) {
  char text[32];
  const auto result = std::to_chars(text, text + sizeof(text), v);
  return std::string(text, result.ptr);
}

std::string formatPoint(const Eigen::Vector3d& p) {
  return formatNumber(p.x()) + "," + formatNumber(p.y()) + "," + formatNumber(p.z());
}

std::string formatPointSpaced(const Eigen::Vector3d& p) {
  return formatNumber(p.x()) + " " + formatNumber(p.y()) + " " + formatNumber(p.z());
}

}  // namespace cenote::cli
