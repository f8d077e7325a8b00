// replay_main.cpp: libFuzzer's entry point driven without libFuzzer, for ctest on any compiler:
// every file of the corpus directories once (the seeds and every crash found, kept as regression
// inputs), then a fixed number of mutations of them drawn from a fixed seed (bit flips, random
// and boundary bytes, erased, inserted and repeated ranges, cuts, splices of two inputs). The same
// arguments give the same inputs on every machine. A crash, a sanitizer report or an exception
// other than cenote::Error (which ends the process through std::terminate) fails the test.
//
//   <harness>_replay CORPUS_DIR... [--mutations N] [--seed S] [--max-size BYTES]
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>
#include <string>
#include <vector>

#include "tests/fuzz/fuzz_input.h"

namespace {

using Bytes = std::vector<uint8_t>;

Bytes readAll(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return Bytes(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

void run(const Bytes& input) { LLVMFuzzerTestOneInput(input.empty() ? nullptr : input.data(), input.size()); }

// One mutation of `input`, with `other` for splices.
void mutate(Bytes& input, const Bytes& other, std::mt19937_64& rng, std::size_t max_size) {
  auto below = [&](std::size_t n) { return n == 0 ? std::size_t{0} : static_cast<std::size_t>(rng() % n); };
  static constexpr uint8_t kBoundary[] = {0x00, 0x01, 0x7F, 0x80, 0xFE, 0xFF};
  switch (rng() % 8) {
    case 0:
      if (!input.empty()) input[below(input.size())] ^= static_cast<uint8_t>(1u << (rng() % 8));
      break;
    case 1:
      if (!input.empty()) input[below(input.size())] = static_cast<uint8_t>(rng());
      break;
    case 2:
      if (!input.empty()) input[below(input.size())] = kBoundary[rng() % sizeof(kBoundary)];
      break;
    case 3: {  // erase a range
      if (input.empty()) break;
      const std::size_t at = below(input.size()), n = 1 + below(std::min<std::size_t>(64, input.size() - at));
      input.erase(input.begin() + static_cast<long>(at), input.begin() + static_cast<long>(at + n));
      break;
    }
    case 4: {  // insert random bytes
      const std::size_t at = below(input.size() + 1), n = 1 + below(16);
      Bytes bytes(n);
      for (uint8_t& b : bytes) b = static_cast<uint8_t>(rng());
      input.insert(input.begin() + static_cast<long>(at), bytes.begin(), bytes.end());
      break;
    }
    case 5: {  // repeat a range
      if (input.empty()) break;
      const std::size_t at = below(input.size()), n = 1 + below(std::min<std::size_t>(32, input.size() - at));
      const Bytes range(input.begin() + static_cast<long>(at), input.begin() + static_cast<long>(at + n));
      input.insert(input.begin() + static_cast<long>(below(input.size() + 1)), range.begin(), range.end());
      break;
    }
    case 6:  // cut short
      input.resize(below(input.size() + 1));
      break;
    case 7: {  // splice: this input's head, the other's tail
      const std::size_t head = below(input.size() + 1), from = below(other.size() + 1);
      input.resize(head);
      input.insert(input.end(), other.begin() + static_cast<long>(from), other.end());
      break;
    }
  }
  if (input.size() > max_size) input.resize(max_size);
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::filesystem::path> dirs;
  long mutations = 1000;
  uint64_t seed = 1;
  std::size_t max_size = 1 << 20;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--mutations" && i + 1 < argc) {
      mutations = std::atol(argv[++i]);
    } else if (arg == "--seed" && i + 1 < argc) {
      seed = std::strtoull(argv[++i], nullptr, 10);
    } else if (arg == "--max-size" && i + 1 < argc) {
      max_size = std::strtoull(argv[++i], nullptr, 10);
    } else {
      dirs.emplace_back(arg);
    }
  }
  std::vector<std::filesystem::path> files;
  for (const auto& dir : dirs) {
    if (!std::filesystem::is_directory(dir)) {
      std::fprintf(stderr, "fuzz replay: %s is not a directory\n", dir.c_str());
      return 2;
    }
    for (const auto& entry : std::filesystem::directory_iterator(dir)) {
      if (entry.is_regular_file()) files.push_back(entry.path());
    }
  }
  std::sort(files.begin(), files.end());  // the same order everywhere
  if (files.empty()) {
    std::fprintf(stderr, "fuzz replay: no corpus files\n");
    return 2;
  }
  std::vector<Bytes> corpus;
  for (const auto& file : files) {
    corpus.push_back(readAll(file));
    run(corpus.back());
  }
  std::mt19937_64 rng(seed);
  for (long i = 0; i < mutations; ++i) {
    Bytes input = corpus[rng() % corpus.size()];
    const int steps = 1 + static_cast<int>(rng() % 4);
    for (int s = 0; s < steps; ++s) mutate(input, corpus[rng() % corpus.size()], rng, max_size);
    run(input);
  }
  std::printf("fuzz replay: %zu corpus files and %ld mutations (seed %llu) ran\n", files.size(), mutations,
              static_cast<unsigned long long>(seed));
  return 0;
}
