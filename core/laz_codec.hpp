// The entropy decoder under LAZ (rapidlasso, "LAZ specification 1.4", sections "arithmetic
// coder" and "integer compressor"): an adaptive arithmetic decoder in the style of Said's
// FastAC with binary and multi-symbol models, and the integer decompressor that codes the
// difference between a value and its prediction as a bit-length class k plus the k-bit
// correction within that class.
//
// Robustness: the decoder never reads outside the span it was given. Reading past its end
// yields zero bytes and is counted (overrun()), so a truncated or corrupt chunk decodes to
// garbage in bounded time and the caller reports it; every table index derived from the
// stream is clamped to its table.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

namespace treelobes::laz {

// Adaptive probability of a 0 bit (spec: "ArithmeticBitModel").
class BitModel {
public:
    BitModel();

private:
    friend class ArithmeticDecoder;
    void update();

    std::uint32_t bit0_prob_, bit0_count_, bit_count_, update_cycle_, bits_until_update_;
};

// Adaptive distribution over `symbols` symbols (2..2048; spec: "ArithmeticModel"). Models with
// more than 16 symbols keep a lookup table that narrows the interval search.
class SymbolModel {
public:
    explicit SymbolModel(std::uint32_t symbols);
    std::uint32_t symbols() const { return symbols_; }

private:
    friend class ArithmeticDecoder;
    void update();

    std::uint32_t symbols_, last_symbol_;
    std::uint32_t table_shift_ = 0, table_size_ = 0;
    std::uint32_t total_count_ = 0, update_cycle_ = 0, symbols_until_update_ = 0;
    std::vector<std::uint32_t> distribution_, counts_, table_;
};

class ArithmeticDecoder {
public:
    // Starts decoding `size` bytes at `data` (the first four bytes prime the code value).
    void init(const std::uint8_t* data, std::size_t size);

    std::uint32_t decode_bit(BitModel& model);
    std::uint32_t decode_symbol(SymbolModel& model);
    // Raw (equiprobable) values of up to 32 bits.
    std::uint32_t read_bits(std::uint32_t bits);
    std::uint32_t read_short();
    std::uint32_t read_int();

    // Bytes requested beyond the end of the data (0 for an intact stream).
    std::size_t overrun() const { return overrun_; }
    std::size_t consumed() const { return pos_; }

private:
    std::uint8_t next_byte() {
        if (pos_ < size_) return data_[pos_++];
        ++overrun_;
        return 0;
    }
    void renormalize();

    const std::uint8_t* data_ = nullptr;
    std::size_t size_ = 0, pos_ = 0, overrun_ = 0;
    std::uint32_t value_ = 0, length_ = 0;
};

// Decodes integers predicted by `pred`: the stored corrector c (real = pred + c, wrapped into
// the value range) is coded as its bit length k under one of `contexts` symbol models, then
// the k-bit offset (the upper `bits_high` bits modelled, the rest raw). Spec: "integer
// compressor"; `bits` is the value width, `range` an optional explicit value range.
class IntegerDecompressor {
public:
    IntegerDecompressor(ArithmeticDecoder& decoder, std::uint32_t bits = 16, std::uint32_t contexts = 1, std::uint32_t bits_high = 8,
                        std::uint32_t range = 0);

    std::int32_t decompress(std::int32_t pred, std::uint32_t context = 0);
    // Bit length class of the last corrector: LAZ uses it as context for the next coordinate.
    std::uint32_t k() const { return k_; }

private:
    std::int32_t read_corrector(SymbolModel& model);

    ArithmeticDecoder* decoder_;
    std::uint32_t bits_high_, corr_bits_ = 0, corr_range_ = 0;
    std::int32_t corr_min_ = 0;
    std::uint32_t k_ = 0;
    std::vector<SymbolModel> k_models_;  // one per context, corr_bits + 1 symbols
    BitModel zero_corrector_;            // k == 0: the corrector is 0 or 1
    // Class k = 1..corr_bits at index k - 1, created on first use: a fresh model's state is
    // fixed, so creating it late decodes the same, and small chunks (COPC nodes) skip building
    // models for classes they never see.
    std::vector<std::optional<SymbolModel>> correctors_;
    SymbolModel& corrector(std::uint32_t k);
};

}  // namespace treelobes::laz
