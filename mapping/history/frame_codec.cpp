#include "mapping/history/frame_codec.h"

#include <libdeflate.h>

#include <cstring>
#include <algorithm>
#include <memory>

#include "common/error.h"
#include "mapping/detail/block_table.h"

namespace cenote::mapping::history {
namespace {

void putVarint(std::string& out, uint64_t v) {
  while (v >= 0x80) {
    out.push_back(static_cast<char>((v & 0x7f) | 0x80));
    v >>= 7;
  }
  out.push_back(static_cast<char>(v));
}
uint64_t zigzag(int64_t v) { return (static_cast<uint64_t>(v) << 1) ^ static_cast<uint64_t>(v >> 63); }
int64_t unzigzag(uint64_t v) { return static_cast<int64_t>(v >> 1) ^ -static_cast<int64_t>(v & 1); }

void putWord(std::string& out, uint64_t w) {
  char bytes[8];
  std::memcpy(bytes, &w, 8);
  out.append(bytes, 8);
}

// Reads what put* wrote; every read checks the bounds.
class Reader {
 public:
  Reader(const std::string& bytes, const std::string& where) : bytes_(bytes), where_(where) {}
  uint64_t varint() {
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
  void skip(size_t n) {
    if (bytes_.size() - pos_ < n) fail("it ends early");
    pos_ += n;
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
  void finish() const {
    if (pos_ != bytes_.size()) fail("bytes are left over");
  }
  [[noreturn]] void fail(const std::string& what) const {
    throw IoError("frame store: " + where_ + " does not decode: " + what);
  }

 private:
  const std::string& bytes_;
  const std::string& where_;
  size_t pos_ = 0;
};

std::string deflate(const std::string& raw, int level) {
  std::unique_ptr<libdeflate_compressor, decltype(&libdeflate_free_compressor)> c(libdeflate_alloc_compressor(level),
                                                                                  libdeflate_free_compressor);
  if (!c) throw ResourceExhaustedError("frame store: cannot allocate a deflate compressor");
  std::string out;
  putVarint(out, raw.size());
  const size_t header = out.size();
  out.resize(header + libdeflate_deflate_compress_bound(c.get(), raw.size()));
  const size_t n = libdeflate_deflate_compress(c.get(), raw.data(), raw.size(), out.data() + header, out.size() - header);
  out.resize(header + n);
  return out;
}

std::string inflate(const std::string& packed, const std::string& where) {
  Reader r(packed, where);
  const uint64_t raw_size = r.varint();
  size_t header = 0;
  while (static_cast<uint8_t>(packed[header]) & 0x80) ++header;
  ++header;
  if (raw_size > (uint64_t{1} << 34)) r.fail("a section larger than 16 GiB");
  std::unique_ptr<libdeflate_decompressor, decltype(&libdeflate_free_decompressor)> d(libdeflate_alloc_decompressor(),
                                                                                      libdeflate_free_decompressor);
  if (!d) throw ResourceExhaustedError("frame store: cannot allocate a deflate decompressor");
  std::string raw(raw_size, '\0');
  size_t actual = 0;
  if (libdeflate_deflate_decompress(d.get(), packed.data() + header, packed.size() - header, raw.data(), raw.size(),
                                    &actual) != LIBDEFLATE_SUCCESS ||
      actual != raw_size) {
    r.fail("its deflate stream is broken");
  }
  return raw;
}

// The updates of a raw (inflated) section; keep_all, or only the blocks `keep` lists (ascending:
// merged with the section's ascending keys). A kept block's colours are those whose voxel lies in
// it; colours come in endpoint order, mostly several in one block after another, so the last
// block's answer is reused.
FrameUpdates decodeRaw(const std::string& raw, const std::string& where, std::span<const uint64_t> keep, bool keep_all) {
  Reader r(raw, where);
  FrameUpdates out;
  const size_t n = r.count(129);
  if (keep_all) out.keys.reserve(n);
  uint64_t previous = 0;
  size_t next_keep = 0;
  for (size_t b = 0; b < n; ++b) {
    const uint64_t key = previous + r.varint();
    if (b > 0 && key <= previous) r.fail("block keys not ascending");
    previous = key;
    while (next_keep < keep.size() && keep[next_keep] < key) ++next_keep;
    const bool kept = keep_all || (next_keep < keep.size() && keep[next_keep] == key);
    if (!kept) {
      r.skip(16 * 8);
      out.others.push_back(key);
      continue;
    }
    out.keys.push_back(key);
    if (!keep_all) out.kept_at.push_back(static_cast<uint32_t>(next_keep));
    BlockMasks& masks = out.masks.emplace_back();
    for (uint64_t& w : masks.free) w = r.word();
    for (uint64_t& w : masks.hit) w = r.word();
  }
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
  std::string raw;
  raw.reserve(points.quantised.size() * 5 + points.colors.size() * 3 + 16);
  putVarint(raw, points.quantised.size());
  Eigen::Vector3i previous = Eigen::Vector3i::Zero();
  for (const Eigen::Vector3i& q : points.quantised) {
    for (int k = 0; k < 3; ++k) putVarint(raw, zigzag(static_cast<int64_t>(q[k]) - previous[k]));
    previous = q;
  }
  putVarint(raw, points.colors.size());
  for (const auto& rgb : points.colors) raw.append(reinterpret_cast<const char*>(rgb.data()), 3);
  return deflate(raw, level);
}

FramePoints decodePoints(const std::string& bytes, const std::string& where) {
  const std::string raw = inflate(bytes, where);
  Reader r(raw, where);
  FramePoints out;
  out.quantised.resize(r.count(3));
  Eigen::Vector3i previous = Eigen::Vector3i::Zero();
  for (Eigen::Vector3i& q : out.quantised) {
    for (int k = 0; k < 3; ++k) q[k] = static_cast<int>(previous[k] + unzigzag(r.varint()));
    previous = q;
  }
  out.colors.resize(r.count(3));
  for (auto& rgb : out.colors) {
    for (int k = 0; k < 3; ++k) rgb[k] = r.byte();
  }
  r.finish();
  return out;
}

std::string encodeUpdates(const FrameUpdates& updates, int level) {
  std::string raw;
  raw.reserve(updates.keys.size() * 140 + updates.colors.size() * 8 + 16);
  putVarint(raw, updates.keys.size());
  uint64_t previous = 0;
  for (size_t b = 0; b < updates.keys.size(); ++b) {
    putVarint(raw, updates.keys[b] - previous);
    previous = updates.keys[b];
    for (uint64_t w : updates.masks[b].free) putWord(raw, w);
    for (uint64_t w : updates.masks[b].hit) putWord(raw, w);
  }
  putVarint(raw, updates.colors.size());
  VoxelIndex last = VoxelIndex::Zero();
  for (const EndpointColor& c : updates.colors) {
    for (int k = 0; k < 3; ++k) putVarint(raw, zigzag(static_cast<int64_t>(c.ijk[k]) - last[k]));
    last = c.ijk;
    raw.append(reinterpret_cast<const char*>(c.rgb.data()), 3);
  }
  return deflate(raw, level);
}

FrameUpdates decodeUpdates(const std::string& bytes, const std::string& where) {
  const std::string raw = inflate(bytes, where);
  return decodeRaw(raw, where, {}, true);
}

FrameUpdates decodeUpdates(const std::string& bytes, const std::string& where, std::span<const uint64_t> keep) {
  const std::string raw = inflate(bytes, where);
  return decodeRaw(raw, where, keep, false);
}

}  // namespace cenote::mapping::history
