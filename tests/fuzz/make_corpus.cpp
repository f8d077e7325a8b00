// make_corpus.cpp: writes the seed corpora of the fuzz harnesses (corpus/<harness>/), each file
// made by an independent writer: PNG and JPEG by OpenCV, OctoMap trees by OctoMap, frames by
// protobuf around OpenCV's images, PLY by hand (bytes of the format), the configuration by
// copying config/default.yaml. Run once and commit the files:
//   build/tests/fuzz/fuzz_make_corpus tests/fuzz/corpus .
#include <octomap/ColorOcTree.h>
#include <octomap/OcTree.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "cenote/v1/ingest.pb.h"

namespace {

namespace fs = std::filesystem;

void write(const fs::path& path, const std::string& bytes) {
  fs::create_directories(path.parent_path());
  std::ofstream(path, std::ios::binary) << bytes;
  std::printf("%s: %zu bytes\n", path.c_str(), bytes.size());
}

std::string encode(const std::string& ext, const cv::Mat& image, const std::vector<int>& params = {}) {
  std::vector<uint8_t> bytes;
  if (!cv::imencode(ext, image, bytes, params)) throw std::runtime_error("cannot encode " + ext);
  return std::string(bytes.begin(), bytes.end());
}

// Smooth gradients with a little noise: small files that still exercise every filter and code.
cv::Mat image(int rows, int cols, int type, int seed) {
  cv::Mat m(rows, cols, type);
  cv::Mat noise(rows, cols, type);
  cv::theRNG().state = static_cast<uint64_t>(seed);
  cv::randu(noise, 0, 16);
  for (int y = 0; y < rows; ++y) {
    for (int x = 0; x < cols * m.channels(); ++x) {
      const int v = (x * 3 + y * 5) % 200 + noise.ptr<uint8_t>(y)[x % (cols * m.channels())];
      if (m.depth() == CV_8U) m.ptr<uint8_t>(y)[x] = static_cast<uint8_t>(v);
      if (m.depth() == CV_16U) m.ptr<uint16_t>(y)[x] = static_cast<uint16_t>(v * 300);
    }
  }
  return m;
}

std::string octree(bool binary, bool colour, bool pruned) {
  std::stringstream out;
  if (colour) {
    octomap::ColorOcTree tree(0.1);
    for (int i = 0; i < 6; ++i) tree.updateNode(0.1 * i, 0.05, 0.05, i % 2 == 0)->setColor(200, 40 * i, 10);
    tree.write(out);
  } else {
    octomap::OcTree tree(0.1);
    for (int i = 0; i < 6; ++i) tree.updateNode(0.1 * i, 0.05, 0.05, i % 3 != 0);
    if (pruned) {
      for (int x = 0; x < 2; ++x)
        for (int y = 0; y < 2; ++y)
          for (int z = 0; z < 2; ++z) tree.updateNode(1.05 + 0.1 * x, 1.05 + 0.1 * y, 1.05 + 0.1 * z, true);
      tree.prune();
    }
    if (binary) {
      tree.writeBinary(out);
    } else {
      tree.write(out);
    }
  }
  return out.str();
}

std::string frame(const std::string& left, const std::string& right, bool pose) {
  cenote::v1::StereoFrame f;
  f.set_timestamp_s(12.5);
  f.mutable_left()->set_encoded(left);
  f.mutable_right()->set_encoded(right);
  if (pose) {
    f.mutable_pose()->mutable_orientation()->set_w(1.0);
    f.mutable_pose()->mutable_position()->set_x(0.5);
  }
  return f.SerializeAsString();
}

std::string rawFrame() {
  cenote::v1::StereoFrame f;
  f.set_timestamp_s(3.0);
  const cv::Mat grey = image(48, 64, CV_8UC1, 9), bgr = image(48, 64, CV_8UC3, 10);
  cenote::v1::RawImage* left = f.mutable_left()->mutable_raw();
  left->set_width(64);
  left->set_height(48);
  left->set_encoding(cenote::v1::IMAGE_ENCODING_MONO8);
  left->set_data(std::string(reinterpret_cast<const char*>(grey.data), grey.total()));
  cenote::v1::RawImage* right = f.mutable_right()->mutable_raw();
  right->set_width(64);
  right->set_height(48);
  right->set_encoding(cenote::v1::IMAGE_ENCODING_RGB8);
  right->set_data(std::string(reinterpret_cast<const char*>(bgr.data), bgr.total() * 3));
  return f.SerializeAsString();
}

std::string ply(int points) {
  std::string out = "ply\nformat binary_little_endian 1.0\ncomment seed\nelement vertex " + std::to_string(points) +
                    "\nproperty float x\nproperty float y\nproperty float z\nproperty uchar red\n"
                    "property uchar green\nproperty uchar blue\nend_header\n";
  for (int i = 0; i < points; ++i) {
    const float xyz[3] = {0.5f * i, -1.0f, 2.0f + i};
    out.append(reinterpret_cast<const char*>(xyz), sizeof(xyz));
    out += static_cast<char>(10 * i);
    out += static_cast<char>(200);
    out += static_cast<char>(30);
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: fuzz_make_corpus CORPUS_DIR SOURCE_DIR\n");
    return 2;
  }
  const fs::path dir = argv[1], source = argv[2];
  // Images: the kinds frames and datasets hold, and two damaged ones.
  const fs::path images = dir / "image_decode";
  const std::string jpeg = encode(".jpg", image(24, 32, CV_8UC3, 1));
  const std::string png = encode(".png", image(24, 32, CV_8UC1, 2));
  write(images / "grey.png", png);
  write(images / "bgr.png", encode(".png", image(24, 32, CV_8UC3, 3)));
  write(images / "bgra.png", encode(".png", image(16, 16, CV_8UC4, 4)));
  write(images / "grey16.png", encode(".png", image(16, 16, CV_16UC1, 5)));
  write(images / "colour.jpg", jpeg);
  write(images / "grey.jpg", encode(".jpg", image(24, 32, CV_8UC1, 6)));
  write(images / "progressive.jpg", encode(".jpg", image(24, 32, CV_8UC3, 7), {cv::IMWRITE_JPEG_PROGRESSIVE, 1}));
  write(images / "cut.jpg", jpeg.substr(0, jpeg.size() / 2));
  write(images / "no_iend.png", png.substr(0, png.size() - 12));
  // PLY: three points, none.
  write(dir / "ply_reader" / "three.ply", ply(3));
  write(dir / "ply_reader" / "empty.ply", ply(0));
  // Map files: first byte 0 for .bt, 1 for .ot (map_file_fuzz.cpp).
  write(dir / "map_file" / "tree.bt", std::string(1, '\0') + octree(true, false, false));
  write(dir / "map_file" / "pruned.bt", std::string(1, '\0') + octree(true, false, true));
  write(dir / "map_file" / "tree.ot", std::string(1, '\1') + octree(false, false, false));
  write(dir / "map_file" / "colour.ot", std::string(1, '\1') + octree(false, true, false));
  // Frames of the calibrated 64x48 (frame_decoder_fuzz.cpp).
  const std::string left = encode(".png", image(48, 64, CV_8UC1, 8));
  const std::string right = encode(".jpg", image(48, 64, CV_8UC3, 11));
  write(dir / "frame_decoder" / "png_jpeg.pb", frame(left, right, true));
  write(dir / "frame_decoder" / "jpeg_png.pb", frame(right, left, false));
  write(dir / "frame_decoder" / "raw.pb", rawFrame());
  // Configuration: the defaults, and a short file of a few sections.
  std::ifstream defaults(source / "config" / "default.yaml");
  write(dir / "config_yaml" / "default.yaml", std::string(std::istreambuf_iterator<char>(defaults), {}));
  write(dir / "config_yaml" / "short.yaml",
        "map:\n  voxel_size_m: 0.1\nstereo:\n  num_paths: 8\nserver:\n  limits:\n    max_batch: 10\n");
  return 0;
}
