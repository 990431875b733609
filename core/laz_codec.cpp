// LAZ arithmetic decoder and integer decompressor; see laz_codec.hpp. Constants and update rules
// follow the LAZ specification 1.4 ("arithmetic coder": 32-bit interval, renormalisation below
// 2^24, binary models with 13-bit and symbol models with 15-bit probabilities, adaptive update
// periods growing by 5/4 up to a cap).
#include "core/laz_codec.hpp"

#include "core/error.hpp"

#include <algorithm>

namespace treelobes::laz {

namespace {

constexpr std::uint32_t kMinLength = 0x01000000u;  // renormalise when the interval drops below 2^24
constexpr std::uint32_t kMaxLength = 0xFFFFFFFFu;
constexpr std::uint32_t kBitLengthShift = 13;  // binary probabilities have 13 bits
constexpr std::uint32_t kBitMaxCount = 1u << kBitLengthShift;
constexpr std::uint32_t kSymbolLengthShift = 15;  // symbol distributions have 15 bits
constexpr std::uint32_t kSymbolMaxCount = 1u << kSymbolLengthShift;

}  // namespace

// ---------------------------------------------------------------------------------------------
// Models

BitModel::BitModel() : bit0_prob_(1u << (kBitLengthShift - 1)), bit0_count_(1), bit_count_(2), update_cycle_(4), bits_until_update_(4) {}

void BitModel::update() {
    // Halve the counts when they grow too large, so the model keeps adapting.
    if ((bit_count_ += update_cycle_) > kBitMaxCount) {
        bit_count_ = (bit_count_ + 1) >> 1;
        bit0_count_ = (bit0_count_ + 1) >> 1;
        if (bit0_count_ == bit_count_) ++bit_count_;
    }
    const std::uint32_t scale = 0x80000000u / bit_count_;
    bit0_prob_ = (bit0_count_ * scale) >> (31 - kBitLengthShift);
    update_cycle_ = std::min<std::uint32_t>((5 * update_cycle_) >> 2, 64);
    bits_until_update_ = update_cycle_;
}

SymbolModel::SymbolModel(std::uint32_t symbols) : symbols_(symbols), last_symbol_(symbols - 1) {
    if (symbols < 2 || symbols > 2048) throw Error(ExitCode::Internal, "LAZ symbol model with " + std::to_string(symbols) + " symbols");
    if (symbols > 16) {
        std::uint32_t table_bits = 3;
        while (symbols > (1u << (table_bits + 2))) ++table_bits;
        table_size_ = 1u << table_bits;
        table_shift_ = kSymbolLengthShift - table_bits;
        table_.assign(table_size_ + 2, 0);
    }
    distribution_.assign(symbols, 0);
    counts_.assign(symbols, 1);
    update_cycle_ = symbols;
    update();
    symbols_until_update_ = update_cycle_ = (symbols + 6) >> 1;
}

void SymbolModel::update() {
    if ((total_count_ += update_cycle_) > kSymbolMaxCount) {
        total_count_ = 0;
        for (std::uint32_t& c : counts_) total_count_ += (c = (c + 1) >> 1);
    }
    const std::uint32_t scale = 0x80000000u / total_count_;
    std::uint32_t sum = 0;
    if (table_size_ == 0) {
        for (std::uint32_t k = 0; k < symbols_; ++k) {
            distribution_[k] = (scale * sum) >> (31 - kSymbolLengthShift);
            sum += counts_[k];
        }
    } else {
        // table_[t] is the first symbol whose interval may contain values with top bits t.
        std::uint32_t s = 0;
        for (std::uint32_t k = 0; k < symbols_; ++k) {
            distribution_[k] = (scale * sum) >> (31 - kSymbolLengthShift);
            sum += counts_[k];
            const std::uint32_t w = distribution_[k] >> table_shift_;
            while (s < w) table_[++s] = k - 1;
        }
        table_[0] = 0;
        while (s <= table_size_) table_[++s] = symbols_ - 1;
    }
    update_cycle_ = std::min((5 * update_cycle_) >> 2, (symbols_ + 6) << 3);
    symbols_until_update_ = update_cycle_;
}

// ---------------------------------------------------------------------------------------------
// Decoder

void ArithmeticDecoder::init(const std::uint8_t* data, std::size_t size) {
    data_ = data;
    size_ = size;
    pos_ = 0;
    overrun_ = 0;
    length_ = kMaxLength;
    value_ = 0;
    for (int i = 0; i < 4; ++i) value_ = (value_ << 8) | next_byte();
}

void ArithmeticDecoder::renormalize() {
    do {
        value_ = (value_ << 8) | next_byte();
    } while ((length_ <<= 8) < kMinLength);
}

std::uint32_t ArithmeticDecoder::decode_bit(BitModel& m) {
    const std::uint32_t x = m.bit0_prob_ * (length_ >> kBitLengthShift);
    const std::uint32_t bit = value_ >= x ? 1 : 0;
    if (bit == 0) {
        length_ = x;
        ++m.bit0_count_;
    } else {
        value_ -= x;
        length_ -= x;
    }
    if (length_ < kMinLength) renormalize();
    if (--m.bits_until_update_ == 0) m.update();
    return bit;
}

std::uint32_t ArithmeticDecoder::decode_symbol(SymbolModel& m) {
    std::uint32_t symbol, x, y = length_;
    if (!m.table_.empty()) {
        length_ >>= kSymbolLengthShift;
        const std::uint32_t dv = value_ / length_;
        // A corrupt stream can leave value >= length; clamp instead of indexing past the table.
        const std::uint32_t t = std::min(dv >> m.table_shift_, m.table_size_);
        symbol = m.table_[t];
        std::uint32_t n = m.table_[t + 1] + 1;
        while (n > symbol + 1) {  // bisection inside the table's bracket
            const std::uint32_t k = (symbol + n) >> 1;
            if (m.distribution_[k] > dv)
                n = k;
            else
                symbol = k;
        }
        x = m.distribution_[symbol] * length_;
        if (symbol != m.last_symbol_) y = m.distribution_[symbol + 1] * length_;
    } else {
        x = symbol = 0;
        length_ >>= kSymbolLengthShift;
        std::uint32_t n = m.symbols_;
        std::uint32_t k = n >> 1;
        do {  // bisection over all symbols
            const std::uint32_t z = length_ * m.distribution_[k];
            if (z > value_) {
                n = k;
                y = z;
            } else {
                symbol = k;
                x = z;
            }
        } while ((k = (symbol + n) >> 1) != symbol);
    }
    value_ -= x;
    length_ = y - x;
    if (length_ < kMinLength) renormalize();
    ++m.counts_[symbol];
    if (--m.symbols_until_update_ == 0) m.update();
    return symbol;
}

std::uint32_t ArithmeticDecoder::read_bits(std::uint32_t bits) {
    if (bits > 19) {  // split so that length >> bits keeps enough precision
        const std::uint32_t low = read_short();
        const std::uint32_t high = read_bits(bits - 16);
        return (high << 16) | low;
    }
    const std::uint32_t symbol = value_ / (length_ >>= bits);
    value_ -= length_ * symbol;
    if (length_ < kMinLength) renormalize();
    return symbol;
}

std::uint32_t ArithmeticDecoder::read_short() {
    const std::uint32_t symbol = value_ / (length_ >>= 16);
    value_ -= length_ * symbol;
    if (length_ < kMinLength) renormalize();
    return symbol & 0xFFFFu;
}

std::uint32_t ArithmeticDecoder::read_int() {
    const std::uint32_t low = read_short();
    const std::uint32_t high = read_short();
    return (high << 16) | low;
}

// ---------------------------------------------------------------------------------------------
// Integer decompressor

IntegerDecompressor::IntegerDecompressor(ArithmeticDecoder& decoder, std::uint32_t bits, std::uint32_t contexts, std::uint32_t bits_high,
                                         std::uint32_t range)
        : decoder_(&decoder), bits_high_(bits_high) {
    if (range != 0) {  // explicit range: as many bits as it takes
        corr_range_ = range;
        while (range != 0) {
            range >>= 1;
            ++corr_bits_;
        }
        if (corr_range_ == (1u << (corr_bits_ - 1))) --corr_bits_;
        corr_min_ = -static_cast<std::int32_t>(corr_range_ / 2);
    } else if (bits != 0 && bits < 32) {
        corr_bits_ = bits;
        corr_range_ = 1u << bits;
        corr_min_ = -static_cast<std::int32_t>(corr_range_ / 2);
    } else {  // full 32-bit range: wrapping is implicit
        corr_bits_ = 32;
        corr_range_ = 0;
        corr_min_ = INT32_MIN;
    }
    k_models_.reserve(contexts);
    for (std::uint32_t c = 0; c < contexts; ++c) k_models_.emplace_back(corr_bits_ + 1);
    correctors_.resize(corr_bits_);
}

SymbolModel& IntegerDecompressor::corrector(std::uint32_t k) {
    std::optional<SymbolModel>& model = correctors_[k - 1];
    if (!model) model.emplace(k <= bits_high_ ? 1u << k : 1u << bits_high_);
    return *model;
}

std::int32_t IntegerDecompressor::decompress(std::int32_t pred, std::uint32_t context) {
    const std::int32_t corrector = read_corrector(k_models_[context]);
    // Wrap pred + corrector into [0, range) (the whole 32-bit circle when range is 0).
    std::int64_t real = std::int64_t{pred} + corrector;
    if (corr_range_ != 0) {
        if (real < 0)
            real += corr_range_;
        else if (real >= std::int64_t{corr_range_})
            real -= corr_range_;
    }
    return static_cast<std::int32_t>(static_cast<std::uint32_t>(real));
}

std::int32_t IntegerDecompressor::read_corrector(SymbolModel& model) {
    k_ = decoder_->decode_symbol(model);
    if (k_ == 0) return static_cast<std::int32_t>(decoder_->decode_bit(zero_corrector_));
    if (k_ >= 32) return corr_min_;
    std::int64_t c;
    if (k_ <= bits_high_) {
        c = decoder_->decode_symbol(corrector(k_));
    } else {  // the high bits are modelled, the k - bits_high low bits are raw
        const std::uint32_t raw_bits = k_ - bits_high_;
        const std::int64_t high = decoder_->decode_symbol(corrector(k_));
        c = (high << raw_bits) | decoder_->read_bits(raw_bits);
    }
    // Class k holds the correctors with |c| in [2^(k-1), 2^k): offsets below 2^(k-1) are the
    // negative ones, the others the positive ones.
    if (c >= (std::int64_t{1} << (k_ - 1)))
        c += 1;
    else
        c -= (std::int64_t{1} << k_) - 1;
    return static_cast<std::int32_t>(c);
}

}  // namespace treelobes::laz
