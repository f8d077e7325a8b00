// cli_input.h: what cenote-cli reads from its command line and files: points "X,Y,Z", points
// files (one "x y z" a line), the token file, and the formatting of vectors in its output.
// Bad input throws CliError naming the argument or the file and line.
// Units: metres. Threads: pure functions.
#pragma once

#include <Eigen/Core>
#include <stdexcept>
#include <string>
#include <vector>

namespace cenote::cli {

class CliError : public std::runtime_error {
 public:
  explicit CliError(const std::string& message) : std::runtime_error(message) {}
};

// "1.0,-2,0.5" -> (1, -2, 0.5); `what` names the argument in the error ("--from").
Eigen::Vector3d parsePoint(const std::string& text, const std::string& what);
// One "x y z" (spaces, tabs or commas) per line; blank lines and lines starting with '#' skipped.
std::vector<Eigen::Vector3d> readPointsFile(const std::string& path);
// The shortest text that reads back as the same double ("2.025", "1234567.5").
std::string formatNumber(double v);
// "x,y,z" / "x y z" with formatNumber.
std::string formatPoint(const Eigen::Vector3d& p);
std::string formatPointSpaced(const Eigen::Vector3d& p);

}  // namespace cenote::cli
