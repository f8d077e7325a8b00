#include "pipeline/calibration/stereo_calibration.h"

#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <utility>

#include "common/atomic_file.h"
#include "common/error.h"
#include "io/image/image_io.h"

namespace cenote::pipeline {
namespace {

void requireFile(const std::string& path) {
  if (!std::filesystem::exists(path)) throw NotFoundError("calibration file not found: " + path);
}

cv::Mat readMatrix(const cv::FileNode& parent, const std::string& path, std::initializer_list<const char*> names, int rows,
                   int cols, bool required) {
  for (const char* name : names) {
    cv::FileNode node = parent.isMap() ? parent[name] : cv::FileNode();
    if (node.empty()) continue;
    cv::Mat m;
    node >> m;
    if (m.empty()) throw Error(path + ": " + name + " is not a matrix");
    m.convertTo(m, CV_64F);
    if (rows > 0 && m.total() != static_cast<size_t>(rows * cols)) {
      throw Error(path + ": " + name + " must have " + std::to_string(rows * cols) + " values, has " +
                  std::to_string(m.total()));
    }
    return rows > 0 ? m.reshape(1, rows) : m.reshape(1, 1);
  }
  if (required) throw Error(path + ": missing " + std::string(*names.begin()));
  return {};
}

std::vector<double> toVector(const cv::Mat& m) {
  std::vector<double> v;
  for (size_t i = 0; i < m.total(); ++i) v.push_back(m.at<double>(static_cast<int>(i)));
  return v;
}

StereoGeometry geometryFromProjections(const cv::Matx34d& P_left, const cv::Matx34d& P_right, const cv::Size& size) {
  StereoGeometry g;
  g.fx = P_left(0, 0);
  g.fy = P_left(1, 1);
  g.cx = P_left(0, 2);
  g.cy = P_left(1, 2);
  // P_right = K [I | t] with t = (-b, 0, 0) relative to the left camera (both relative to the
  // same reference camera, as KITTI's P0..P3 are).
  g.baseline_m = (P_left(0, 3) - P_right(0, 3)) / P_right(0, 0);
  g.image_size = size;
  return g;
}

// Opens a FileStorage calibration file and reads its image size, the first keys of both layouts.
// `what` names the file's kind in errors ("calibration", "intrinsics").
cv::Size openWithImageSize(cv::FileStorage& fs, const std::string& path, const std::string& what) {
  requireFile(path);
  try {
    fs.open(path, cv::FileStorage::READ);
  } catch (const cv::Exception& e) {
    throw Error(path + ": not a readable " + what + " file: " + e.what());
  }
  if (!fs.isOpened()) throw Error(path + ": not a readable " + what + " file");
  int width = 0, height = 0;
  fs["image_width"] >> width;
  fs["image_height"] >> height;
  // The reference paper's own files (github.com/ApdowJN/RTDense3DMapping) write `size: [w, h]`.
  const cv::FileNode size = fs["size"];
  if (width <= 0 && height <= 0 && size.isSeq() && size.size() == 2) {
    width = static_cast<int>(size[0]);
    height = static_cast<int>(size[1]);
  }
  if (width <= 0 || height <= 0) throw Error(path + ": missing image_width / image_height");
  return cv::Size(width, height);
}

// `c`, validated; a failed rule names `path`, the file (or files) it was read from.
StereoCalibration validated(StereoCalibration c, const std::string& path) {
  try {
    c.validate();
  } catch (const Error& e) {
    throw Error(path + ": " + e.what());
  }
  return c;
}

}  // namespace

void StereoCalibration::validate() const {
  if (image_size.width <= 0 || image_size.height <= 0) throw Error("calibration: image size is empty");
  if (rectified) {
    const StereoGeometry& g = rectified_geometry;
    if (!(g.fx > 0 && g.fy > 0)) throw Error("calibration: rectified focal length must be positive");
    if (!(std::abs(g.baseline_m) > 1e-9)) throw Error("calibration: rectified baseline is zero");
    return;
  }
  for (const CameraIntrinsics* cam : {&left, &right}) {
    const char* which = cam == &left ? "left" : "right";
    if (!(cam->K(0, 0) > 0 && cam->K(1, 1) > 0)) {
      throw Error(std::string("calibration: ") + which + " focal length must be positive");
    }
    const size_t n = cam->distortion.size();
    if (!(n == 0 || n == 4 || n == 5 || n == 8)) {
      throw Error(std::string("calibration: ") + which + " distortion must have 4, 5 or 8 coefficients, has " +
                  std::to_string(n));
    }
  }
  const cv::Matx33d should_be_identity = R.t() * R;
  if (cv::norm(should_be_identity - cv::Matx33d::eye()) > 1e-6 || cv::determinant(R) < 0) {
    throw Error("calibration: R is not a rotation matrix");
  }
  if (cv::norm(T) < 1e-9) throw Error("calibration: baseline T is zero");
}

StereoCalibration readStereoCalibration(const std::string& path) {
  cv::FileStorage fs;
  StereoCalibration c;
  c.image_size = openWithImageSize(fs, path, "calibration");
  const cv::Mat P1 = readMatrix(fs.root(), path, {"P1"}, 3, 4, false);
  const cv::Mat K1 = readMatrix(fs.root(), path, {"K1", "M1"}, 3, 3, false);
  if (K1.empty() && !P1.empty()) {
    const cv::Mat P2 = readMatrix(fs.root(), path, {"P2"}, 3, 4, true);
    c.rectified = true;
    c.rectified_geometry = geometryFromProjections(cv::Matx34d(P1), cv::Matx34d(P2), c.image_size);
  } else {
    if (K1.empty()) throw Error(path + ": missing K1 (or P1/P2 for a rectified rig)");
    c.left.K = cv::Matx33d(K1);
    c.right.K = cv::Matx33d(readMatrix(fs.root(), path, {"K2", "M2"}, 3, 3, true));
    c.left.distortion = toVector(readMatrix(fs.root(), path, {"D1"}, 0, 0, false));
    c.right.distortion = toVector(readMatrix(fs.root(), path, {"D2"}, 0, 0, false));
    c.R = cv::Matx33d(readMatrix(fs.root(), path, {"R"}, 3, 3, true));
    const cv::Mat T = readMatrix(fs.root(), path, {"T"}, 3, 1, true);
    c.T = cv::Vec3d(T.at<double>(0), T.at<double>(1), T.at<double>(2));
  }
  return validated(std::move(c), path);
}

void writeStereoCalibration(const std::string& path, const StereoCalibration& c) {
  // YAML whatever the extension, as before (the temporary file keeps the target's extension).
  writeAtomically(path, Durability::kDurable, [&](const std::string& tmp) {
    cv::FileStorage fs(tmp, cv::FileStorage::WRITE | cv::FileStorage::FORMAT_YAML);
    if (!fs.isOpened()) throw IoError("cannot write " + path);
    fs << "image_width" << c.image_size.width << "image_height" << c.image_size.height;
    fs << "K1" << cv::Mat(c.left.K) << "D1" << cv::Mat(c.left.distortion, true);
    fs << "K2" << cv::Mat(c.right.K) << "D2" << cv::Mat(c.right.distortion, true);
    fs << "R" << cv::Mat(c.R) << "T" << cv::Mat(c.T);
    fs.release();
  });
}

StereoCalibration readPaperIntrinsics(const std::string& path) {
  cv::FileStorage fs;
  StereoCalibration c;
  c.image_size = openWithImageSize(fs, path, "intrinsics");
  // Each camera as K1 D1 / K2 D2 (or K_left ...) at the top, or as the paper's own files have it:
  // `left:` and `right:` mappings holding K and D.
  const auto camera = [&](const char* side, std::initializer_list<const char*> K, std::initializer_list<const char*> D) {
    CameraIntrinsics cam;
    cv::Mat k = readMatrix(fs.root(), path, K, 3, 3, false);
    if (k.empty()) k = readMatrix(fs[side], path, {"K"}, 3, 3, false);
    if (k.empty()) throw Error(path + ": missing " + std::string(*K.begin()));
    cam.K = cv::Matx33d(k);
    cv::Mat d = readMatrix(fs.root(), path, D, 0, 0, false);
    if (d.empty()) d = readMatrix(fs[side], path, {"D"}, 0, 0, false);
    cam.distortion = toVector(d);
    return cam;
  };
  c.left = camera("left", {"K1", "K_left"}, {"D1", "D_left"});
  c.right = camera("right", {"K2", "K_right"}, {"D2", "D_right"});
  const cv::FileNode baseline_node = fs["baseline"];
  if (baseline_node.empty() || (!baseline_node.isReal() && !baseline_node.isInt()))
    throw Error(path + ": missing baseline (millimetres)");
  const double baseline_mm = static_cast<double>(baseline_node);
  if (!(baseline_mm > 0))
    throw Error(path + ": baseline = " + std::to_string(baseline_mm) + ": must be positive (millimetres)");
  const cv::Mat R = readMatrix(fs.root(), path, {"R"}, 3, 3, false);
  if (!R.empty()) c.R = cv::Matx33d(R);
  const cv::Mat T = readMatrix(fs.root(), path, {"T"}, 3, 1, false);
  if (T.empty()) {
    c.T = cv::Vec3d(-baseline_mm * 1e-3, 0.0, 0.0);
  } else {
    const cv::Vec3d t(T.at<double>(0), T.at<double>(1), T.at<double>(2));
    const double length = cv::norm(t);
    if (std::abs(length - baseline_mm) <= 0.01 * baseline_mm) {
      c.T = t * 1e-3;
    } else if (std::abs(length * 1e3 - baseline_mm) <= 0.01 * baseline_mm) {
      c.T = t;
    } else {
      throw Error(path + ": T has length " + std::to_string(length) +
                  ", which matches baseline = " + std::to_string(baseline_mm) + " mm neither in millimetres nor in metres");
    }
  }
  return validated(std::move(c), path);
}

namespace {

// EuRoC files start with "%YAML:1.0", which is OpenCV's spelling, not YAML's.
YAML::Node loadEurocYaml(const std::string& path) {
  requireFile(path);
  std::ifstream in(path);
  std::stringstream text;
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("%YAML", 0) == 0) continue;
    text << line << "\n";
  }
  try {
    return YAML::Load(text.str());
  } catch (const YAML::Exception& e) {
    throw Error(path + ": not valid YAML: " + e.what());
  }
}

template <typename T>
std::vector<T> readList(const YAML::Node& root, const std::string& path, const std::string& key, size_t n) {
  const YAML::Node node = root[key];
  if (!node) throw Error(path + ": missing " + key);
  std::vector<T> values;
  try {
    values = node.as<std::vector<T>>();
  } catch (const YAML::Exception&) {
    throw Error(path + ": " + key + " must be a list of numbers");
  }
  if (n > 0 && values.size() != n) {
    throw Error(path + ": " + key + " must have " + std::to_string(n) + " values, has " + std::to_string(values.size()));
  }
  return values;
}

}  // namespace

cv::Matx44d readEurocBodyFromSensor(const std::string& path) {
  const YAML::Node root = loadEurocYaml(path);
  const YAML::Node tbs = root["T_BS"];
  if (!tbs) throw Error(path + ": missing T_BS");
  const std::vector<double> data = readList<double>(tbs, path, "data", 16);
  cv::Matx44d T;
  for (int i = 0; i < 16; ++i) T.val[i] = data[i];
  return T;
}

StereoCalibration readEurocSensorPair(const std::string& left_path, const std::string& right_path) {
  StereoCalibration c;
  cv::Matx44d T_body_cam[2];
  for (int i = 0; i < 2; ++i) {
    const std::string& path = i == 0 ? left_path : right_path;
    const YAML::Node root = loadEurocYaml(path);
    if (root["distortion_model"] && root["distortion_model"].as<std::string>() != "radial-tangential" &&
        root["distortion_model"].as<std::string>() != "radtan") {
      throw Error(path + ": distortion_model " + root["distortion_model"].as<std::string>() +
                  " is not supported (radial-tangential only)");
    }
    const auto k = readList<double>(root, path, "intrinsics", 4);
    const auto resolution = readList<int>(root, path, "resolution", 2);
    CameraIntrinsics& cam = i == 0 ? c.left : c.right;
    cam.K = cv::Matx33d(k[0], 0, k[2], 0, k[1], k[3], 0, 0, 1);
    cam.distortion = readList<double>(root, path, "distortion_coefficients", 0);
    const cv::Size size(resolution[0], resolution[1]);
    if (i == 0) c.image_size = size;
    if (i == 1 && size != c.image_size) {
      throw Error(right_path + ": resolution differs from the left camera's");
    }
    T_body_cam[i] = readEurocBodyFromSensor(path);
  }
  // p_right = T_right_left * p_left, T_right_left = inv(T_body_right) * T_body_left.
  const cv::Matx44d T_right_left = T_body_cam[1].inv() * T_body_cam[0];
  c.R = T_right_left.get_minor<3, 3>(0, 0);
  c.T = cv::Vec3d(T_right_left(0, 3), T_right_left(1, 3), T_right_left(2, 3));
  return validated(std::move(c), left_path + " + " + right_path);
}

StereoCalibration readKittiCalibration(const std::string& path, const cv::Size& image_size, const std::string& left,
                                       const std::string& right) {
  requireFile(path);
  std::ifstream in(path);
  std::string line;
  cv::Matx34d P[2];
  bool found[2] = {false, false};
  while (std::getline(in, line)) {
    const auto colon = line.find(':');
    if (colon == std::string::npos) continue;
    const std::string key = line.substr(0, colon);
    for (int i = 0; i < 2; ++i) {
      if (key != (i == 0 ? left : right)) continue;
      std::istringstream values(line.substr(colon + 1));
      for (int j = 0; j < 12; ++j) {
        if (!(values >> P[i].val[j])) throw Error(path + ": row " + key + " must have 12 numbers");
      }
      found[i] = true;
    }
  }
  for (int i = 0; i < 2; ++i) {
    if (!found[i]) throw Error(path + ": missing row " + (i == 0 ? left : right));
  }
  StereoCalibration c;
  c.image_size = image_size;
  c.rectified = true;
  c.rectified_geometry = geometryFromProjections(P[0], P[1], image_size);
  c.validate();
  return c;
}

namespace {

enum class CalibrationFileKind { kOpenCv, kEuroc, kKitti, kPaper };

// KITTI: a line "P0:" (or P1..P3) followed by 12 numbers (OpenCV's rectified layout has "P1:" keys
// too, followed by a matrix); EuRoC / Kalibr: T_BS and intrinsics keys; the paper's intrinsics.yaml:
// a baseline key.
CalibrationFileKind calibrationFileKind(const std::string& path) {
  std::ifstream in(path);
  std::string line;
  bool t_bs = false, intrinsics = false, baseline = false;
  while (std::getline(in, line)) {
    if (line.size() > 2 && line[0] == 'P' && line[1] >= '0' && line[1] <= '3' && line[2] == ':') {
      std::istringstream values(line.substr(3));
      int numbers = 0;
      for (double v; values >> v;) ++numbers;
      if (numbers == 12) return CalibrationFileKind::kKitti;
    }
    t_bs = t_bs || line.rfind("T_BS:", 0) == 0;
    intrinsics = intrinsics || line.rfind("intrinsics:", 0) == 0;
    baseline = baseline || line.rfind("baseline:", 0) == 0;
  }
  if (t_bs && intrinsics) return CalibrationFileKind::kEuroc;
  return baseline ? CalibrationFileKind::kPaper : CalibrationFileKind::kOpenCv;
}

}  // namespace

StereoCalibration readCalibrationFile(const std::string& path, cv::Size image_size) {
  namespace fs = std::filesystem;
  requireFile(path);
  if (fs::is_directory(path)) {
    throw Error(path + ": is a folder; a calibration file is expected (OpenCV stereo YAML, EuRoC cam0/sensor.yaml, "
                       "KITTI calib.txt)");
  }
  const fs::path dir = fs::path(path).parent_path();
  switch (calibrationFileKind(path)) {
    case CalibrationFileKind::kKitti: {
      const bool colour = fs::is_directory(dir / "image_2") && fs::is_directory(dir / "image_3");
      const fs::path first = dir / (colour ? "image_2" : "image_0") / "000000.png";
      if (fs::exists(first)) image_size = io::readImage(first.string(), cv::IMREAD_UNCHANGED).size();
      if (image_size.empty()) {
        throw Error(path + ": a KITTI calib.txt has no image size, and there is no " + first.string() +
                    " beside it to take it from");
      }
      return readKittiCalibration(path, image_size, colour ? "P2" : "P0", colour ? "P3" : "P1");
    }
    case CalibrationFileKind::kEuroc: {
      if (dir.filename() != "cam0") {
        throw Error(path + ": an EuRoC / Kalibr sensor.yaml describes one camera; give the left camera's, "
                           "<mav0>/cam0/sensor.yaml, with cam1/sensor.yaml beside it");
      }
      const fs::path right = dir.parent_path() / "cam1" / fs::path(path).filename();
      if (!fs::exists(right)) {
        throw Error(path + ": the right camera's " + right.string() +
                    " is missing (an EuRoC / Kalibr sensor.yaml "
                    "describes one camera)");
      }
      return readEurocSensorPair(path, right.string());
    }
    case CalibrationFileKind::kPaper: return readPaperIntrinsics(path);
    case CalibrationFileKind::kOpenCv: break;
  }
  try {
    return readStereoCalibration(path);
  } catch (const Error& e) {
    throw Error(std::string(e.what()) +
                " (calibration files read: OpenCV stereo YAML with image_width, image_height, K1 D1 K2 D2 R T or P1 "
                "P2; EuRoC / Kalibr cam0/sensor.yaml beside cam1/sensor.yaml; KITTI calib.txt)");
  }
}

}  // namespace cenote::pipeline
