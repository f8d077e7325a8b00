#include "io/image/rle_deflate.h"

#include <libdeflate.h>

#include <algorithm>
#include <array>
#include <cstring>

#include "io/image/big_endian.h"

namespace cenote::io {
namespace {

constexpr std::size_t kBlockBytes = 64 * 1024;  // one Huffman code per block (adapts to the content)
constexpr int kEndOfBlock = 256;
constexpr int kFirstLengthSymbol = 257;
constexpr int kLiteralLengthSymbols = 286;  // 0-255 literals, 256 end of block, 257-285 lengths
constexpr int kDistanceSymbols = 2;         // distance 1 (code 0), and code 1 to make a complete code
constexpr int kCodeLengthSymbols = 19;
constexpr int kMinRun = 3, kMaxRun = 258;  // deflate's match lengths
constexpr int kMaxCodeBits = 15;           // deflate's limit for literal/length and distance codes
constexpr int kMaxCodeLengthBits = 7;      // and for the code of the code lengths
// The order in which a dynamic block header sends the code-length code (RFC 1951, 3.2.7).
constexpr std::array<uint8_t, kCodeLengthSymbols> kCodeLengthOrder = {16, 17, 18, 0, 8,  7, 9,  6, 10, 5,
                                                                      11, 4,  12, 3, 13, 2, 14, 1, 15};

// Length symbol, extra bits and their value of a match length in [3, 258] (RFC 1951, 3.2.5).
struct LengthCode {
  uint16_t symbol;
  uint8_t extra_bits;
  uint8_t extra;
};

constexpr std::array<LengthCode, kMaxRun + 1> makeLengthCodes() {
  constexpr std::array<int, 29> kBase = {3,  4,  5,  6,  7,  8,  9,  10, 11,  13,  15,  17,  19,  23, 27,
                                         31, 35, 43, 51, 59, 67, 83, 99, 115, 131, 163, 195, 227, 258};
  constexpr std::array<int, 29> kExtra = {0, 0, 0, 0, 0, 0, 0, 0, 1, 1, 1, 1, 2, 2, 2,
                                          2, 3, 3, 3, 3, 4, 4, 4, 4, 5, 5, 5, 5, 0};
  std::array<LengthCode, kMaxRun + 1> codes{};
  for (int k = 0; k < 29; ++k) {
    const int last = k + 1 < 29 ? kBase[k + 1] - 1 : kMaxRun;
    for (int length = kBase[k]; length <= last; ++length) {
      codes[length] = {static_cast<uint16_t>(kFirstLengthSymbol + k), static_cast<uint8_t>(kExtra[k]),
                       static_cast<uint8_t>(length - kBase[k])};
    }
  }
  return codes;
}
constexpr std::array<LengthCode, kMaxRun + 1> kLengthCodes = makeLengthCodes();

// Little-endian bit packing as deflate wants it; the output must have 8 bytes of slack past the end.
class BitWriter {
 public:
  explicit BitWriter(uint8_t* out) : out_(out) {}
  // Up to 7 bits stay pending after flush(), so up to 57 bits may be put between two flushes.
  void put(uint32_t bits, int count) {
    pending_ |= static_cast<uint64_t>(bits) << count_;
    count_ += count;
  }
  void flush() {
    std::memcpy(out_, &pending_, sizeof(pending_));
    out_ += count_ >> 3;
    pending_ >>= count_ & ~7;
    count_ &= 7;
  }
  // Pads to a whole byte; @return one past the last byte written.
  uint8_t* finish() {
    flush();
    if (count_ > 0) *out_++ = static_cast<uint8_t>(pending_);
    pending_ = 0;
    count_ = 0;
    return out_;
  }

 private:
  uint8_t* out_;
  uint64_t pending_ = 0;
  int count_ = 0;
};

// Splits data[begin, end) into literals and runs, calling literals(first, count) for bytes coded
// as themselves and run(length) for `length` (in [3, 258]) copies of the byte before. Runs are
// looked for 8 bytes at a time (a word equal to the previous byte repeated), so noisy data costs
// one comparison per 8 bytes; a run starting inside a word begins at the next word.
template <class Literals, class Run>
void tokenize(const uint8_t* data, std::size_t begin, std::size_t end, Literals literals, Run run) {
  std::size_t i = begin;
  while (i + 8 <= end) {
    uint64_t word;
    std::memcpy(&word, data + i, sizeof(word));
    const uint64_t repeated = i == 0 ? ~word : data[i - 1] * 0x0101010101010101ULL;
    if (word != repeated) {
      literals(data + i, 8);
      i += 8;
      continue;
    }
    std::size_t j = i + 8;
    while (j + 8 <= end && std::memcmp(data + j, &repeated, sizeof(repeated)) == 0) j += 8;
    while (j < end && data[j] == data[i - 1]) ++j;
    for (std::size_t left = j - i; left > 0;) {
      if (left < kMinRun) {
        literals(data + j - left, left);
        break;
      }
      const std::size_t length = std::min<std::size_t>(left, kMaxRun);
      run(static_cast<int>(length));
      left -= length;
    }
    i = j;
  }
  if (i < end) literals(data + i, end - i);
}

// Huffman code lengths for freq[0, n) (0 for unused symbols), none longer than max_bits. Fewer
// than two used symbols get two codes of length 1 (inflaters demand a complete code). Halving the
// frequencies until the longest code fits keeps it a Huffman code (complete), only a little longer.
void codeLengths(const uint32_t* freq, int n, int max_bits, uint8_t* lengths) {
  constexpr int kMaxSymbols = kLiteralLengthSymbols;
  std::array<int, kMaxSymbols> symbol{};
  std::fill(lengths, lengths + n, 0);
  int used = 0;
  for (int s = 0; s < n; ++s) {
    if (freq[s] > 0) symbol[used++] = s;
  }
  if (used < 2) {
    const int only = used == 1 ? symbol[0] : 0;
    lengths[only] = 1;
    lengths[only == 0 ? 1 : 0] = 1;
    return;
  }
  // Leaves sorted by frequency (ties by symbol: the same code on every machine).
  std::sort(symbol.begin(), symbol.begin() + used,
            [&](int a, int b) { return freq[a] != freq[b] ? freq[a] < freq[b] : a < b; });
  std::array<uint32_t, 2 * kMaxSymbols> weight{};
  std::array<int, 2 * kMaxSymbols> parent{}, depth{};
  for (int shift = 0;; ++shift) {
    for (int i = 0; i < used; ++i) weight[i] = std::max<uint32_t>(1, freq[symbol[i]] >> shift);
    // The two-queue construction: nodes [used, next) are created in non-decreasing weight.
    int leaf = 0, node = used, next = used;
    auto smallest = [&] { return leaf < used && (node >= next || weight[leaf] <= weight[node]) ? leaf++ : node++; };
    for (; next < 2 * used - 1; ++next) {
      const int a = smallest(), b = smallest();
      weight[next] = weight[a] + weight[b];
      parent[a] = parent[b] = next;
    }
    depth[2 * used - 2] = 0;
    int longest = 0;
    for (int i = 2 * used - 3; i >= 0; --i) {
      depth[i] = depth[parent[i]] + 1;
      if (i < used) longest = std::max(longest, depth[i]);
    }
    if (longest <= max_bits) {
      for (int i = 0; i < used; ++i) lengths[symbol[i]] = static_cast<uint8_t>(depth[i]);
      return;
    }
  }
}

// Canonical codes of the given lengths (RFC 1951, 3.2.2), bit-reversed for the LSB-first writer.
void canonicalCodes(const uint8_t* lengths, int n, uint16_t* codes) {
  std::array<int, kMaxCodeBits + 1> count{}, next{};
  for (int s = 0; s < n; ++s) ++count[lengths[s]];
  count[0] = 0;
  for (int bits = 1, code = 0; bits <= kMaxCodeBits; ++bits) {
    code = (code + count[bits - 1]) << 1;
    next[bits] = code;
  }
  for (int s = 0; s < n; ++s) {
    const int length = lengths[s];
    if (length == 0) continue;
    uint32_t code = static_cast<uint32_t>(next[length]++), reversed = 0;
    for (int b = 0; b < length; ++b, code >>= 1) reversed = (reversed << 1) | (code & 1);
    codes[s] = static_cast<uint16_t>(reversed);
  }
}

// A Huffman code: length and bit-reversed code per symbol.
template <int kSymbols>
struct HuffmanCode {
  std::array<uint8_t, kSymbols> lengths{};
  std::array<uint16_t, kSymbols> codes{};
  HuffmanCode(const std::array<uint32_t, kSymbols>& freq, int max_bits) {
    codeLengths(freq.data(), kSymbols, max_bits, lengths.data());
    canonicalCodes(lengths.data(), kSymbols, codes.data());
  }
  void put(int symbol, BitWriter& out) const { out.put(codes[symbol], lengths[symbol]); }
};

// Block header after BFINAL and BTYPE: the literal/length and distance code lengths, coded with
// a code-length code of symbols 0-15 (no repeat symbols: a few hundred bits per 64 KB block).
void writeCodeLengths(const HuffmanCode<kLiteralLengthSymbols>& literal_length, BitWriter& out) {
  std::array<uint8_t, kLiteralLengthSymbols + kDistanceSymbols> lengths{};
  std::copy(literal_length.lengths.begin(), literal_length.lengths.end(), lengths.begin());
  std::fill(lengths.begin() + kLiteralLengthSymbols, lengths.end(), 1);  // distance codes "0" and "1"
  std::array<uint32_t, kCodeLengthSymbols> freq{};
  for (uint8_t length : lengths) ++freq[length];
  const HuffmanCode<kCodeLengthSymbols> code_lengths(freq, kMaxCodeLengthBits);
  int sent = kCodeLengthSymbols;
  while (sent > 4 && code_lengths.lengths[kCodeLengthOrder[sent - 1]] == 0) --sent;

  out.put(kLiteralLengthSymbols - 257, 5);      // HLIT
  out.put(kDistanceSymbols - 1, 5);             // HDIST
  out.put(static_cast<uint32_t>(sent - 4), 4);  // HCLEN
  out.flush();
  for (int i = 0; i < sent; ++i) {
    out.put(code_lengths.lengths[kCodeLengthOrder[i]], 3);
    out.flush();
  }
  for (uint8_t length : lengths) {
    code_lengths.put(length, out);
    out.flush();
  }
}

// One dynamic-Huffman block (RFC 1951, 3.2.7) of data[begin, end).
void writeBlock(const uint8_t* data, std::size_t begin, std::size_t end, bool last, BitWriter& out) {
  std::array<uint32_t, kLiteralLengthSymbols> freq{};
  tokenize(
      data, begin, end,
      [&](const uint8_t* bytes, std::size_t count) {
        for (std::size_t k = 0; k < count; ++k) ++freq[bytes[k]];
      },
      [&](int length) { ++freq[kLengthCodes[length].symbol]; });
  freq[kEndOfBlock] = 1;
  const HuffmanCode<kLiteralLengthSymbols> code(freq, kMaxCodeBits);

  out.put(last ? 1 : 0, 1);
  out.put(2, 2);  // dynamic Huffman codes
  writeCodeLengths(code, out);
  tokenize(
      data, begin, end,
      [&](const uint8_t* bytes, std::size_t count) {
        std::size_t k = 0;
        for (; k + 3 <= count; k += 3) {  // 3 codes of at most 15 bits per flush
          code.put(bytes[k], out);
          code.put(bytes[k + 1], out);
          code.put(bytes[k + 2], out);
          out.flush();
        }
        for (; k < count; ++k) code.put(bytes[k], out);
        out.flush();
      },
      [&](int length) {
        const LengthCode& c = kLengthCodes[length];
        code.put(c.symbol, out);
        out.put(c.extra, c.extra_bits);
        out.put(0, 1);  // distance code 0: distance 1
        out.flush();
      });
  code.put(kEndOfBlock, out);
  out.flush();
}

}  // namespace

void deflateRle(const uint8_t* data, std::size_t size, std::vector<uint8_t>& out) {
  // Bound: a literal costs at most 15 bits, a run fewer bits than its bytes; plus the headers.
  const std::size_t blocks = std::max<std::size_t>(1, (size + kBlockBytes - 1) / kBlockBytes);
  const std::size_t bound = 2 + 2 * size + 400 * blocks + 4 + 8;
  // Written here first, then copied: growing `out` by the bound would zero megabytes per call.
  thread_local std::vector<uint8_t> scratch;
  if (scratch.size() < bound) scratch.resize(bound);
  uint8_t* p = scratch.data();
  *p++ = 0x78;  // deflate, 32 KB window
  *p++ = 0x01;  // fastest compression, no dictionary; (0x78 * 256 + 0x01) % 31 == 0
  BitWriter bits(p);
  for (std::size_t b = 0; b < blocks; ++b) {
    const std::size_t first = b * kBlockBytes;
    writeBlock(data, first, std::min(size, first + kBlockBytes), b + 1 == blocks, bits);
  }
  p = bits.finish();
  storeBigEndian32(p, libdeflate_adler32(1, data, size));
  p += 4;
  out.insert(out.end(), scratch.data(), p);
}

}  // namespace cenote::io
