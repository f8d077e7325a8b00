#include "common/text_parse.h"

#include <cstdlib>
#include <sstream>

namespace cenote {

bool parseNumberList(const std::string& text, char separator, std::vector<double>& values, std::string* bad_item) {
  values.clear();
  std::istringstream in(text);
  std::string item;
  while (std::getline(in, item, separator)) {
    char* end = nullptr;
    const double v = std::strtod(item.c_str(), &end);
    if (item.empty() || end == item.c_str() || *end != '\0') {
      if (bad_item) *bad_item = item;
      return false;
    }
    values.push_back(v);
  }
  return true;
}

std::optional<Eigen::Vector3d> parsePoint(const std::string& text) {
  std::vector<double> v;
  if (!parseNumberList(text, ',', v) || v.size() != 3) return std::nullopt;
  return Eigen::Vector3d(v[0], v[1], v[2]);
}

}  // namespace cenote
