#include "encode/bitstream.hpp"

#include "core/error.hpp"

#include <bit>
#include <utility>

namespace treelobes::encode {

void BitWriter::write(std::uint64_t value, unsigned count) {
    while (count > 0) {
        const unsigned used = static_cast<unsigned>(bits_ % 8);
        if (used == 0) bytes_.push_back(0);
        const unsigned free = 8 - used;
        const unsigned take = count < free ? count : free;
        const auto chunk = static_cast<std::uint8_t>((value >> (count - take)) & ((1u << take) - 1));
        bytes_.back() = static_cast<std::uint8_t>(bytes_.back() | (chunk << (free - take)));
        bits_ += take;
        count -= take;
    }
}

BitReader::BitReader(std::span<const std::uint8_t> bytes, std::string context) : bytes_(bytes), context_(std::move(context)) {}

void BitReader::fail(const std::string& what) const { throw Error::input(context_, what); }

std::uint64_t BitReader::read(unsigned count) {
    if (count > bits_left())
        fail("truncated stream (needs " + std::to_string(count) + " more bits at bit " + std::to_string(position_) + ")");
    std::uint64_t value = 0;
    while (count > 0) {
        const unsigned used = static_cast<unsigned>(position_ % 8);
        const unsigned available = 8 - used;
        const unsigned take = count < available ? count : available;
        const unsigned byte = bytes_[position_ / 8];
        const unsigned chunk = (byte >> (available - take)) & ((1u << take) - 1);
        value = (value << take) | chunk;
        position_ += take;
        count -= take;
    }
    return value;
}

void write_elias_gamma(BitWriter& out, std::uint64_t v) {
    if (v == 0) throw Error(ExitCode::Internal, "Elias gamma code of 0");
    const unsigned width = bit_width64(v);
    out.write(0, width - 1);
    out.write(v, width);
}

std::uint64_t read_elias_gamma(BitReader& in) {
    unsigned zeros = 0;
    while (!in.read_bit()) {
        if (++zeros > 63) in.fail("invalid Elias gamma code (more than 63 leading zeros)");
    }
    return zeros == 0 ? 1 : ((std::uint64_t{1} << zeros) | in.read(zeros));
}

void write_elias_delta(BitWriter& out, std::uint64_t v) {
    if (v == 0) throw Error(ExitCode::Internal, "Elias delta code of 0");
    const unsigned width = bit_width64(v);
    write_elias_gamma(out, width);
    out.write(v, width - 1);  // the leading 1 is implied by the width
}

std::uint64_t read_elias_delta(BitReader& in) {
    const std::uint64_t width = read_elias_gamma(in);
    if (width > 64) in.fail("invalid Elias delta code (value wider than 64 bits)");
    const auto low_bits = static_cast<unsigned>(width - 1);
    const std::uint64_t high = low_bits == 64 ? 0 : (std::uint64_t{1} << low_bits);
    return high | in.read(low_bits);
}

void write_count(BitWriter& out, std::uint64_t v) {
    if (v == UINT64_MAX) throw Error(ExitCode::Internal, "count too large for the bit stream");
    write_elias_delta(out, v + 1);
}

std::uint64_t read_count(BitReader& in) {
    const std::uint64_t v = read_elias_delta(in);
    if (v == 0) in.fail("invalid count");
    return v - 1;
}

namespace {

// Range sizes are limited so that 2^b never overflows; interpolative ranges stay far below.
constexpr std::uint64_t kMaxRange = std::uint64_t{1} << 62;

struct MinimalBinaryShape {
    unsigned long_bits;         // b = ceil(log2 n)
    std::uint64_t short_count;  // 2^b - n values coded with b - 1 bits
    std::uint64_t start;        // first value of the centred short block
};

MinimalBinaryShape shape_of(std::uint64_t n) {
    const unsigned b = bit_width64(n - 1);
    const std::uint64_t short_count = (std::uint64_t{1} << b) - n;
    return {b, short_count, (n - short_count) / 2};
}

}  // namespace

void write_centred_minimal_binary(BitWriter& out, std::uint64_t x, std::uint64_t n) {
    if (n == 0 || n > kMaxRange || x >= n) throw Error(ExitCode::Internal, "minimal binary code out of range");
    if (n == 1) return;
    const MinimalBinaryShape s = shape_of(n);
    const std::uint64_t rotated = (x + n - s.start) % n;  // the centred block maps to [0, short_count)
    if (rotated < s.short_count)
        out.write(rotated, s.long_bits - 1);
    else
        out.write(rotated + s.short_count, s.long_bits);
}

std::uint64_t read_centred_minimal_binary(BitReader& in, std::uint64_t n) {
    if (n == 0 || n > kMaxRange) in.fail("invalid value range " + std::to_string(n));
    if (n == 1) return 0;
    const MinimalBinaryShape s = shape_of(n);
    std::uint64_t v = in.read(s.long_bits - 1);
    if (v >= s.short_count) v = ((v << 1) | in.read(1)) - s.short_count;
    return (v + s.start) % n;
}

unsigned centred_minimal_binary_length(std::uint64_t x, std::uint64_t n) {
    if (n <= 1) return 0;
    const MinimalBinaryShape s = shape_of(n);
    const std::uint64_t rotated = (x + n - s.start) % n;
    return rotated < s.short_count ? s.long_bits - 1 : s.long_bits;
}

}  // namespace treelobes::encode
