// Bit-level IO for the entropy coders of encode/: an MSB-first bit writer and a reader that never
// touches memory past the end of its buffer. Reading past the end throws Error(InvalidInput), so a
// truncated or corrupt stream ends in a clean error instead of a crash or an endless loop.
//
// Also the integer codes the coders share: Elias gamma/delta for counts without a known bound,
// and the centred minimal binary code (FELICS, Howard & Vitter 1993) that binary interpolative
// coding uses for a value in a known range.
#pragma once

#include <bit>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace treelobes::encode {

class BitWriter {
public:
    // Appends the `count` low bits of `value`, most significant first (count <= 64).
    void write(std::uint64_t value, unsigned count);
    void write_bit(bool bit) { write(bit ? 1u : 0u, 1); }
    std::size_t bit_count() const { return bits_; }
    // The bytes written so far; the last byte is padded with zero bits.
    const std::vector<std::uint8_t>& bytes() const { return bytes_; }
    std::vector<std::uint8_t> take() { return std::move(bytes_); }

private:
    std::vector<std::uint8_t> bytes_;
    std::size_t bits_ = 0;
};

class BitReader {
public:
    // `context` names the stream in errors ("tree.dbf6: LOD 0 code stream").
    BitReader(std::span<const std::uint8_t> bytes, std::string context);
    // Reads `count` bits (<= 64), most significant first; throws Error(InvalidInput) when fewer
    // than `count` bits remain.
    std::uint64_t read(unsigned count);
    bool read_bit() { return read(1) != 0; }
    std::size_t bits_left() const { return bytes_.size() * 8 - position_; }
    std::size_t position() const { return position_; }
    const std::string& context() const { return context_; }
    // Throws Error(InvalidInput) with "<context>: <what>".
    [[noreturn]] void fail(const std::string& what) const;

private:
    std::span<const std::uint8_t> bytes_;
    std::size_t position_ = 0;
    std::string context_;
};

// Number of bits of the binary representation of v (0 for v = 0).
inline unsigned bit_width64(std::uint64_t v) { return static_cast<unsigned>(std::bit_width(v)); }  // inline: hot in the coders

// Elias gamma code of v >= 1: floor(log2 v) zeros, then v in binary.
void write_elias_gamma(BitWriter& out, std::uint64_t v);
std::uint64_t read_elias_gamma(BitReader& in);
// Elias delta code of v >= 1 (shorter than gamma for large values).
void write_elias_delta(BitWriter& out, std::uint64_t v);
std::uint64_t read_elias_delta(BitReader& in);
// Convenience: any v >= 0 as delta(v + 1); signed values through the zig-zag map.
void write_count(BitWriter& out, std::uint64_t v);
std::uint64_t read_count(BitReader& in);
inline std::uint64_t zigzag(std::int64_t v) { return (static_cast<std::uint64_t>(v) << 1) ^ static_cast<std::uint64_t>(v >> 63); }
inline std::int64_t unzigzag(std::uint64_t v) { return static_cast<std::int64_t>(v >> 1) ^ -static_cast<std::int64_t>(v & 1); }

// Centred minimal binary code of x in [0, n) (n >= 1). With b = ceil(log2 n), the 2^b - n values
// nearest the centre of the range get b - 1 bits and the others b bits; n = 1 costs nothing.
// The centre gets the short codes because an interpolated middle element is most likely there.
void write_centred_minimal_binary(BitWriter& out, std::uint64_t x, std::uint64_t n);
std::uint64_t read_centred_minimal_binary(BitReader& in, std::uint64_t n);
// Length in bits of that code (used by tests and the interpolative coder's statistics).
unsigned centred_minimal_binary_length(std::uint64_t x, std::uint64_t n);

}  // namespace treelobes::encode
