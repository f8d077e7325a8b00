#include "mapping/history/frame_codec.h"

#include <cstring>
#include <string_view>
#include <algorithm>

#include "common/error.h"
#include "io/compression/zstd_block.h"
#include "mapping/detail/block_table.h"

namespace cenote::mapping::history {
namespace {

// The masks of this many consecutive blocks (in key order) are compressed together: a replay
// decompresses only the groups holding a block it rebuilds. Blocks are in x-major order, so the blocks
// a correction rebuilds are a few runs of a frame's keys; 128 blocks = 16 kB of masks.
constexpr size_t kBlocksPerGroup = 128;

// Writes v as a varint at `at` (at most 10 bytes) and returns the byte after it.
char* writeVarint(char* at, uint64_t v) {
  while (v >= 0x80) {
    *at++ = static_cast<char>((v & 0x7f) | 0x80);
    v >>= 7;
  }
  *at++ = static_cast<char>(v);
  return at;
}
void putVarint(std::string& out, uint64_t v) {
  char bytes[10];
  out.append(bytes, writeVarint(bytes, v) - bytes);
}
uint64_t zigzag(int64_t v) { return (static_cast<uint64_t>(v) << 1) ^ static_cast<uint64_t>(v >> 63); }
int64_t unzigzag(uint64_t v) { return static_cast<int64_t>(v >> 1) ^ -static_cast<int64_t>(v & 1); }

// A mask word: one tag byte for the words most masks hold (none or all of their 64 voxels: a
// ray cone carves whole words, most blocks have no hit), otherwise the tag and the 8 bytes. The
// masks then take a few times fewer bytes before compression, which spends its time per input byte.
enum MaskWordTag : uint8_t { kZeroWord = 0, kFullWord = 1, kLiteralWord = 2 };
void putMaskWord(std::string& out, uint64_t w) {
  if (w == 0 || w == ~0ull) {
    out.push_back(static_cast<char>(w == 0 ? kZeroWord : kFullWord));
    return;
  }
  char bytes[9];
  bytes[0] = static_cast<char>(kLiteralWord);
  std::memcpy(bytes + 1, &w, 8);
  out.append(bytes, 9);
}

// Reads what put* wrote; every read checks the bounds.
class Reader {
 public:
  Reader(std::string_view bytes, const std::string& where) : bytes_(bytes), where_(where) {}
  uint64_t varint() {
    // With the longest varint's 10 bytes left, no bounds check per byte (most point deltas and
    // keys take one or two).
    if (bytes_.size() - pos_ >= 10) {
      const auto* p = reinterpret_cast<const uint8_t*>(bytes_.data()) + pos_;
      uint64_t v = p[0] & 0x7fu;
      size_t n = 1;
      for (int shift = 7; (p[n - 1] & 0x80) != 0; shift += 7) {
        if (n == 10) fail("a varint longer than 10 bytes");
        v |= static_cast<uint64_t>(p[n] & 0x7f) << shift;
        ++n;
      }
      pos_ += n;
      return v;
    }
    uint64_t v = 0;
    for (int shift = 0; shift < 64; shift += 7) {
      const uint8_t b = byte();
      v |= static_cast<uint64_t>(b & 0x7f) << shift;
      if ((b & 0x80) == 0) return v;
    }
    fail("a varint longer than 10 bytes");
  }
  uint8_t byte() {
    if (pos_ >= bytes_.size()) fail("it ends early");
    return static_cast<uint8_t>(bytes_[pos_++]);
  }
  uint64_t word() {
    if (bytes_.size() - pos_ < 8) fail("it ends early");
    uint64_t w;
    std::memcpy(&w, bytes_.data() + pos_, 8);
    pos_ += 8;
    return w;
  }
  size_t count(size_t max_bytes_each) {
    const uint64_t n = varint();
    if (n > (bytes_.size() - pos_) / std::max<size_t>(max_bytes_each, 1) + 1) fail("a count larger than its bytes");
    return static_cast<size_t>(n);
  }
  uint64_t maskWord() {
    switch (byte()) {
      case kZeroWord: return 0;
      case kFullWord: return ~0ull;
      case kLiteralWord: return word();
      default: fail("a mask word of an unknown kind");
    }
  }
  size_t pos() const { return pos_; }
  // The next `n` bytes, skipped.
  std::string_view take(size_t n) {
    if (bytes_.size() - pos_ < n) fail("it ends early");
    pos_ += n;
    return bytes_.substr(pos_ - n, n);
  }
  void finish() const {
    if (pos_ != bytes_.size()) fail("bytes are left over");
  }
  [[noreturn]] void fail(const std::string& what) const {
    throw IoError("frame store: " + where_ + " does not decode: " + what);
  }

 private:
  std::string_view bytes_;
  const std::string& where_;
  size_t pos_ = 0;
};

// Appends varint(raw size) and raw's zstd frame to `out`.
void compressTo(std::string_view raw, int level, std::string& out) {
  putVarint(out, raw.size());
  io::zstdCompressAppend({reinterpret_cast<const uint8_t*>(raw.data()), raw.size()}, level, out);
}

std::string compress(std::string_view raw, int level) {
  std::string out;
  compressTo(raw, level, out);
  return out;
}

// What compressTo wrote, into `raw` (its capacity reused).
void decompressTo(std::string_view packed, const std::string& where, std::string& raw) {
  Reader r(packed, where);
  const uint64_t raw_size = r.varint();
  if (raw_size > (uint64_t{1} << 32) - 1) r.fail("a section larger than 4 GiB");
  const std::string_view frame = packed.substr(r.pos());
  raw.resize(raw_size);
  if (!io::zstdDecompressExactly({reinterpret_cast<const uint8_t*>(frame.data()), frame.size()},
                                 reinterpret_cast<uint8_t*>(raw.data()), raw.size())) {
    r.fail("its zstd frame is broken");
  }
}

std::string decompress(std::string_view packed, const std::string& where) {
  std::string raw;
  decompressTo(packed, where, raw);
  return raw;
}

// The keys of a section's blocks, and the byte size of each group of their masks.
struct SectionIndex {
  std::vector<uint64_t> keys;
  std::vector<size_t> group_bytes;
};

SectionIndex readIndex(std::string_view packed, const std::string& where) {
  const std::string raw = decompress(packed, where);
  Reader r(raw, where);
  SectionIndex index;
  const size_t n = r.count(1);
  index.keys.resize(n);
  uint64_t previous = 0;
  for (size_t b = 0; b < n; ++b) {
    const uint64_t key = previous + r.varint();
    if (b > 0 && key <= previous) r.fail("block keys not ascending");
    index.keys[b] = previous = key;
  }
  index.group_bytes.resize((n + kBlocksPerGroup - 1) / kBlocksPerGroup);
  for (size_t& bytes : index.group_bytes) bytes = r.varint();
  r.finish();
  return index;
}

// The colours of the hit voxels in the blocks `out.keys` lists (all: keep_all). Colours come in
// endpoint order, mostly several in one block after another, so the last block's answer is reused.
void readColors(std::string_view packed, const std::string& where, bool keep_all, FrameUpdates& out) {
  const std::string raw = decompress(packed, where);
  Reader r(raw, where);
  const size_t colors = r.count(6);
  VoxelIndex last = VoxelIndex::Zero();
  uint64_t last_block = 0;
  bool last_kept = false, have_last = false;
  for (size_t i = 0; i < colors; ++i) {
    EndpointColor c;
    for (int k = 0; k < 3; ++k) c.ijk[k] = static_cast<int>(last[k] + unzigzag(r.varint()));
    last = c.ijk;
    for (int k = 0; k < 3; ++k) c.rgb[k] = r.byte();
    const uint64_t block = detail::packIndex(blockOf(c.ijk));
    if (!have_last || block != last_block) {
      last_block = block;
      have_last = true;
      last_kept = keep_all || std::binary_search(out.keys.begin(), out.keys.end(), block);
    }
    if (last_kept) out.colors.push_back(c);
  }
  r.finish();
}

// decodeUpdates: the index first, then only the mask groups holding a kept block, and the colours
// only when a block is kept. `keep` (ascending) is merged with the section's ascending keys.
FrameUpdates decodeSection(const std::string& bytes, const std::string& where, std::span<const uint64_t> keep,
                           bool keep_all) {
  Reader r(bytes, where);
  const std::string_view index_part = r.take(r.varint());
  const std::string_view colors_part = r.take(r.varint());
  const SectionIndex index = readIndex(index_part, where);
  FrameUpdates out;
  std::vector<uint8_t> kept(index.keys.size(), keep_all);
  size_t next_keep = 0;
  for (size_t b = 0; b < index.keys.size(); ++b) {
    const uint64_t key = index.keys[b];
    if (!keep_all) {
      while (next_keep < keep.size() && keep[next_keep] < key) ++next_keep;
      kept[b] = next_keep < keep.size() && keep[next_keep] == key;
    }
    if (!kept[b]) {
      out.others.push_back(key);
      continue;
    }
    out.keys.push_back(key);
    if (!keep_all) out.kept_at.push_back(static_cast<uint32_t>(next_keep));
  }
  out.masks.reserve(out.keys.size());
  for (size_t g = 0; g < index.group_bytes.size(); ++g) {
    const std::string_view group = r.take(index.group_bytes[g]);
    const size_t first = g * kBlocksPerGroup, end = std::min(index.keys.size(), first + kBlocksPerGroup);
    if (std::find(kept.begin() + first, kept.begin() + end, 1) == kept.begin() + end) continue;
    const std::string raw = decompress(group, where);
    Reader words(raw, where);
    for (size_t b = first; b < end; ++b) {
      if (!kept[b]) {
        for (int w = 0; w < 16; ++w) words.maskWord();
        continue;
      }
      BlockMasks& masks = out.masks.emplace_back();
      for (uint64_t& w : masks.free) w = words.maskWord();
      for (uint64_t& w : masks.hit) w = words.maskWord();
    }
    words.finish();
  }
  r.finish();
  if (!out.keys.empty()) readColors(colors_part, where, keep_all, out);
  return out;
}

}  // namespace

FrameUpdates FrameUpdates::of(const BatchUpdates& updates) {
  FrameUpdates out;
  out.keys.reserve(updates.numBlocks());
  out.masks.reserve(updates.numBlocks());
  for (size_t b = 0; b < updates.numBlocks(); ++b) {
    out.keys.push_back(detail::packIndex(updates.block(b)));
    out.masks.push_back(updates.masks(b));
  }
  out.colors = updates.colors();
  return out;
}

std::string encodePoints(const FramePoints& points, int level) {
  // Written through a pointer into a buffer sized for the longest varints (a string appended to
  // byte by byte cost more than the compression after it): the zigzag delta of two int32 takes at
  // most 5 bytes. The buffer is the thread's, kept at its largest size: zero-filling 7 MB for
  // every frame cost more than writing it.
  const size_t n = points.quantised.size();
  thread_local std::string raw;
  const size_t longest = 10 + 15 * n + 10 + 3 * points.colors.size();
  if (raw.size() < longest) raw.resize(longest);
  char* at = writeVarint(raw.data(), n);
  Eigen::Vector3i previous = Eigen::Vector3i::Zero();
  for (const Eigen::Vector3i& q : points.quantised) {
    for (int k = 0; k < 3; ++k) at = writeVarint(at, zigzag(static_cast<int64_t>(q[k]) - previous[k]));
    previous = q;
  }
  at = writeVarint(at, points.colors.size());
  static_assert(sizeof(points.colors[0]) == 3, "colours are packed RGB triples");
  if (!points.colors.empty()) {
    std::memcpy(at, points.colors.data(), 3 * points.colors.size());
    at += 3 * points.colors.size();
  }
  return compress(std::string_view(raw.data(), at - raw.data()), level);
}

namespace {

// The points section (decompressed): visit(i, q) for each stored point in order, its count first
// (points(n)), then the colours into `colors`.
template <typename Points, typename Visit>
void parsePoints(const std::string& raw, const std::string& where, Points points, Visit visit,
                 std::vector<std::array<uint8_t, 3>>& colors) {
  Reader r(raw, where);
  const size_t n = r.count(3);
  points(n);
  Eigen::Vector3i q = Eigen::Vector3i::Zero();
  for (size_t i = 0; i < n; ++i) {
    for (int k = 0; k < 3; ++k) q[k] = static_cast<int>(q[k] + unzigzag(r.varint()));
    visit(i, q);
  }
  colors.resize(r.count(3));
  static_assert(sizeof(std::array<uint8_t, 3>) == 3);
  const std::string_view rgb = r.take(colors.size() * 3);
  if (!rgb.empty()) std::memcpy(colors.data(), rgb.data(), rgb.size());
  r.finish();
}

}  // namespace

FramePoints decodePoints(const std::string& bytes, const std::string& where) {
  const std::string raw = decompress(bytes, where);
  FramePoints out;
  parsePoints(
      raw, where, [&](size_t n) { out.quantised.resize(n); },
      [&](size_t i, const Eigen::Vector3i& q) { out.quantised[i] = q; }, out.colors);
  return out;
}

Eigen::AlignedBox3f decodePointsPosed(const std::string& bytes, const std::string& where,
                                      const Eigen::Isometry3d& T_world_cam, double quantum_m, std::string& raw,
                                      PointBatch& out) {
  decompressTo(bytes, where, raw);
  Eigen::AlignedBox3f box;
  parsePoints(
      raw, where, [&](size_t n) { out.points.resize(n); },
      [&](size_t i, const Eigen::Vector3i& q) {
        out.points[i] = toWorld(T_world_cam, q, quantum_m);
        box.extend(out.points[i]);
      },
      out.colors);
  return box;
}

std::string encodeUpdates(const FrameUpdates& updates, int level) {
  const size_t n = updates.keys.size();
  std::string groups, raw;
  std::vector<uint64_t> group_bytes;
  for (size_t first = 0; first < n; first += kBlocksPerGroup) {
    raw.clear();
    for (size_t b = first; b < std::min(n, first + kBlocksPerGroup); ++b) {
      for (uint64_t w : updates.masks[b].free) putMaskWord(raw, w);
      for (uint64_t w : updates.masks[b].hit) putMaskWord(raw, w);
    }
    const size_t before = groups.size();
    compressTo(raw, level, groups);
    group_bytes.push_back(groups.size() - before);
  }
  raw.clear();
  putVarint(raw, n);
  uint64_t previous = 0;
  for (uint64_t key : updates.keys) {
    putVarint(raw, key - previous);
    previous = key;
  }
  for (uint64_t bytes : group_bytes) putVarint(raw, bytes);
  std::string keys_part, colors_part;
  compressTo(raw, level, keys_part);
  raw.clear();
  putVarint(raw, updates.colors.size());
  VoxelIndex last = VoxelIndex::Zero();
  for (const EndpointColor& e : updates.colors) {
    for (int k = 0; k < 3; ++k) putVarint(raw, zigzag(static_cast<int64_t>(e.ijk[k]) - last[k]));
    last = e.ijk;
    raw.append(reinterpret_cast<const char*>(e.rgb.data()), 3);
  }
  compressTo(raw, level, colors_part);
  std::string out;
  out.reserve(keys_part.size() + colors_part.size() + groups.size() + 20);
  putVarint(out, keys_part.size());
  out += keys_part;
  putVarint(out, colors_part.size());
  out += colors_part;
  out += groups;
  return out;
}

FrameUpdates decodeUpdates(const std::string& bytes, const std::string& where) {
  return decodeSection(bytes, where, {}, true);
}

FrameUpdates decodeUpdates(const std::string& bytes, const std::string& where, std::span<const uint64_t> keep) {
  return decodeSection(bytes, where, keep, false);
}

}  // namespace cenote::mapping::history
