// `cenote calibrate`: stereo calibration from chessboard image pairs. Calibrate in water.
#include <algorithm>
#include <filesystem>
#include <iostream>
#include <regex>

#include "apps/cenote/commands.h"
#include "apps/cenote/subcommand.h"
#include "common/error.h"
#include "pipeline/calibration/chessboard_calibration.h"

namespace cenote::apps {
namespace {
namespace fs = std::filesystem;

struct CalibrateOptions {
  std::string images, left_prefix = "left", right_prefix = "right", board = "9x6", out;
  double square_m = 0.025;
};

// Pairs <left_prefix>NN.ext with <right_prefix>NN.ext in `dir`, in name order.
std::vector<std::pair<std::string, std::string>> findPairs(const CalibrateOptions& o) {
  if (!fs::is_directory(o.images)) throw Error("calibrate: " + o.images + " is not a folder");
  std::vector<std::pair<std::string, std::string>> pairs;
  std::vector<fs::path> lefts;
  for (const auto& entry : fs::directory_iterator(o.images)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind(o.left_prefix, 0) == 0) lefts.push_back(entry.path());
  }
  std::sort(lefts.begin(), lefts.end());
  for (const fs::path& left : lefts) {
    const fs::path right = left.parent_path() / (o.right_prefix + left.filename().string().substr(o.left_prefix.size()));
    if (fs::exists(right)) pairs.emplace_back(left.string(), right.string());
  }
  if (pairs.empty()) {
    throw Error("calibrate: no image pairs " + o.left_prefix + "*/" + o.right_prefix + "* in " + o.images);
  }
  return pairs;
}

cv::Size parseBoard(const std::string& text) {
  static const std::regex pattern("([0-9]+)x([0-9]+)");
  std::smatch m;
  if (!std::regex_match(text, m, pattern)) throw Error("calibrate: --board " + text + ": expected COLSxROWS, e.g. 9x6");
  return {std::stoi(m[1]), std::stoi(m[2])};
}

void run(const CalibrateOptions& o) {
  pipeline::ChessboardSpec board;
  board.inner_corners = parseBoard(o.board);
  board.square_m = o.square_m;
  const auto pairs = findPairs(o);
  const pipeline::ChessboardCalibration result = pipeline::calibrateFromChessboards(pairs, board);
  pipeline::writeStereoCalibration(o.out, result.calibration);
  for (const std::string& r : result.rejected) std::cerr << "skipped " << r << "\n";
  std::cout << "pairs used: " << result.pairs_used << " of " << pairs.size() << "\n"
            << "rms_px=" << result.rms_px << "\n"
            << "rectified_focal_px=" << result.rectified.fx << "\n"
            << "rectified_baseline_m=" << result.rectified.baseline_m << "\n"
            << "calibration written to " << o.out << "\n";
}

}  // namespace

void registerCalibrateCommand(CLI::App& app) {
  const auto [cmd, o] = addSubcommand<CalibrateOptions>(
      app, "calibrate", "Stereo calibration from chessboard image pairs (calibrate in water)", run);
  cmd->add_option("--images", o->images, "Folder with left*/right* image pairs")->required();
  cmd->add_option("--left-prefix", o->left_prefix, "File name prefix of left images")->capture_default_str();
  cmd->add_option("--right-prefix", o->right_prefix, "File name prefix of right images")->capture_default_str();
  cmd->add_option("--board", o->board, "Inner corners COLSxROWS")->capture_default_str();
  cmd->add_option("--square", o->square_m, "Square side in metres")->check(CLI::PositiveNumber)->capture_default_str();
  cmd->add_option("--out", o->out, "Calibration YAML to write")->required();
}

}  // namespace cenote::apps
