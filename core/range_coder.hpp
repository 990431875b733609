// Adaptive binary range coder (the carry-less-cache scheme of LZMA) with probability counters
// that adapt fast while they are young and settle at a fixed rate: tree files are small (a few
// thousand decisions per context), so the first observations must count.
//
// The decoder consumes exactly the bytes the encoder produced; asking for a byte past the end
// throws Error(InvalidInput), so a truncated stream fails instead of decoding garbage.
#pragma once

#include "core/error.hpp"

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace treelobes {

// Probability that the next bit is 0, in 1/65536, plus how many bits it has seen (capped).
struct BitModel {
    std::uint16_t p0 = 32768;
    std::uint8_t seen = 0;

    static constexpr int kLimit = 60;  // then a fixed rate of 1/61: slow drift, little noise
    [[gnu::always_inline]] void update(bool bit) {
        // Rate 1/(seen + 1.5): the first updates are (nearly) frequency counts.
        static constexpr auto rates = [] {
            std::array<std::uint32_t, kLimit + 1> r{};
            for (int i = 0; i <= kLimit; ++i) r[i] = static_cast<std::uint32_t>(65536.0 / (i + 1.5));
            return r;
        }();
        const std::int32_t target = bit ? 0 : 65535;
        const std::int32_t delta = static_cast<std::int32_t>((static_cast<std::int64_t>(target - p0) * rates[seen]) >> 16);
        int p = p0 + delta;
        p = p < 64 ? 64 : (p > 65535 - 64 ? 65535 - 64 : p);
        p0 = static_cast<std::uint16_t>(p);
        seen = static_cast<std::uint8_t>(seen + (seen < kLimit));  // no branch: models of mixed ages alternate
    }
};

class RangeEncoder {
public:
    void encode(BitModel& model, bool bit) {
        const std::uint32_t bound = (range_ >> 16) * model.p0;
        if (!bit) {
            range_ = bound;
        } else {
            low_ += bound;
            range_ -= bound;
        }
        model.update(bit);
        normalize();
    }
    // Equiprobable bits, most significant first.
    void encode_direct(std::uint64_t value, unsigned count) {
        while (count-- > 0) {
            range_ >>= 1;
            if ((value >> count) & 1) low_ += range_;
            normalize();
        }
    }
    std::vector<std::uint8_t> finish() {
        for (int i = 0; i < 5; ++i) shift_low();
        return std::move(out_);
    }

private:
    void normalize() {
        while (range_ < (1u << 24)) {
            range_ <<= 8;
            shift_low();
        }
    }
    void shift_low() {
        if (static_cast<std::uint32_t>(low_) < 0xFF000000u || (low_ >> 32) != 0) {
            const auto carry = static_cast<std::uint8_t>(low_ >> 32);
            std::uint8_t byte = cache_;
            do {
                if (started_) out_.push_back(static_cast<std::uint8_t>(byte + carry));
                started_ = true;  // the very first byte is always 0: not stored
                byte = 0xFF;
            } while (--pending_ != 0);
            cache_ = static_cast<std::uint8_t>(low_ >> 24);
        }
        ++pending_;
        low_ = (low_ & 0x00FFFFFFu) << 8;
    }

    std::uint64_t low_ = 0;
    std::uint32_t range_ = 0xFFFFFFFFu;
    std::uint8_t cache_ = 0;
    std::uint64_t pending_ = 1;
    bool started_ = false;
    std::vector<std::uint8_t> out_;
};

// Thrown by the decoder; out of line so that the decoding loops stay small.
[[noreturn, gnu::cold, gnu::noinline]] inline void fail_decoding(const std::string* context, const char* what) {
    throw Error::input(*context, what);
}

// The decoder's whole state is four plain values and a pointer to the caller's context string:
// a decoder that is a local of a loop whose calls are all inlined lives in registers (with an
// owned string, or methods that pass `this` to an error path, it was loaded from and stored to
// memory around every decision).
class RangeDecoder {
public:
    // `context` names the stream in errors and must outlive the decoder.
    RangeDecoder(std::span<const std::uint8_t> bytes, const std::string& context)
            : next_(bytes.data()), end_(bytes.data() + bytes.size()), context_(&context) {
        for (int i = 0; i < 4; ++i) code_ = (code_ << 8) | next_byte();
    }
    RangeDecoder(std::span<const std::uint8_t>, std::string&&) = delete;  // would dangle

    [[gnu::always_inline]] bool decode(BitModel& model) {
        // Branch-free: the bits of a well-modelled stream are close to random, so a branch on
        // them mispredicts about as often as the stream carries information.
        const std::uint32_t bound = (range_ >> 16) * model.p0;
        const bool bit = code_ >= bound;
        const std::uint32_t mask = 0u - static_cast<std::uint32_t>(bit);
        code_ -= bound & mask;
        range_ = (bound & ~mask) | ((range_ - bound) & mask);
        model.update(bit);
        normalize();
        return bit;
    }
    std::uint64_t decode_direct(unsigned count) {
        std::uint64_t value = 0;
        while (count-- > 0) {
            range_ >>= 1;
            const std::uint32_t mask = 0u - static_cast<std::uint32_t>(code_ >= range_);  // equiprobable: no branch
            code_ -= range_ & mask;
            value = (value << 1) | (mask & 1u);
            normalize();
        }
        return value;
    }
    // True when every byte was consumed (a valid stream ends exactly there).
    bool at_end() const { return next_ == end_; }
    [[noreturn]] void fail(const char* what) const { fail_decoding(context_, what); }

private:
    [[gnu::always_inline]] void normalize() {
        while (range_ < (1u << 24)) {
            range_ <<= 8;
            code_ = (code_ << 8) | next_byte();
        }
    }
    [[gnu::always_inline]] std::uint32_t next_byte() {
        if (next_ == end_) [[unlikely]]
            fail_decoding(context_, "truncated arithmetic-coded stream");
        return *next_++;
    }

    const std::uint8_t* next_;
    const std::uint8_t* end_;
    std::uint32_t range_ = 0xFFFFFFFFu;
    std::uint32_t code_ = 0;
    const std::string* context_;
};

}  // namespace treelobes
