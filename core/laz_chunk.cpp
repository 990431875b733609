// LAZ item models and chunk decoding; see laz_chunk.hpp. Section names refer to rapidlasso's
// "LAZ specification 1.4" (and, for the layered models, "LASzip for LAS 1.4 (native extension)").
#include "core/laz_chunk.hpp"

#include "core/error.hpp"
#include "core/laz_codec.hpp"
#include "core/little_endian.hpp"

#include <algorithm>
#include <array>
#include <cstring>
#include <memory>
#include <optional>

namespace treelobes::laz {

namespace {

// Tolerated read-ahead past a stream's end: the decoder primes four bytes, so an intact stream
// may end up to four bytes before the decoder's window does.
constexpr std::size_t kOverrunSlack = 4;

std::uint8_t fold_u8(std::int32_t n) { return static_cast<std::uint8_t>(n < 0 ? n + 256 : (n > 255 ? n - 256 : n)); }
std::int32_t clamp_u8(std::int32_t n) { return n < 0 ? 0 : (n > 255 ? 255 : n); }
std::uint32_t zero_bit_0(std::uint32_t n) { return n & 0xFFFFFFFEu; }

// A symbol model that is created on first use (the spec creates per-value context models lazily;
// most are never needed in a chunk).
class LazyModel {
public:
    SymbolModel& get(std::uint32_t symbols) {
        if (!model_) model_.emplace(symbols);
        return *model_;
    }

private:
    std::optional<SymbolModel> model_;
};

// Median of the last five values, kept sorted incrementally (spec: "StreamingMedian5"). It
// predicts the next coordinate difference.
class StreamingMedian5 {
public:
    std::int32_t get() const { return v_[2]; }
    void add(std::int32_t x) {
        if (high_) {
            if (x < v_[2]) {
                v_[4] = v_[3];
                v_[3] = v_[2];
                if (x < v_[0]) {
                    v_[2] = v_[1];
                    v_[1] = v_[0];
                    v_[0] = x;
                } else if (x < v_[1]) {
                    v_[2] = v_[1];
                    v_[1] = x;
                } else {
                    v_[2] = x;
                }
            } else {
                if (x < v_[3]) {
                    v_[4] = v_[3];
                    v_[3] = x;
                } else {
                    v_[4] = x;
                }
                high_ = false;
            }
        } else {
            if (v_[2] < x) {
                v_[0] = v_[1];
                v_[1] = v_[2];
                if (v_[4] < x) {
                    v_[2] = v_[3];
                    v_[3] = v_[4];
                    v_[4] = x;
                } else if (v_[3] < x) {
                    v_[2] = v_[3];
                    v_[3] = x;
                } else {
                    v_[2] = x;
                }
            } else {
                if (v_[1] < x) {
                    v_[0] = v_[1];
                    v_[1] = x;
                } else {
                    v_[0] = x;
                }
                high_ = true;
            }
        }
    }

private:
    std::array<std::int32_t, 5> v_{};
    bool high_ = true;
};

std::int32_t wrapping_add(std::int32_t a, std::int32_t b) {
    return static_cast<std::int32_t>(static_cast<std::uint32_t>(a) + static_cast<std::uint32_t>(b));
}
std::int32_t wrapping_mul(std::int32_t a, std::int32_t b) {
    return static_cast<std::int32_t>(static_cast<std::uint32_t>(a) * static_cast<std::uint32_t>(b));
}

// ---------------------------------------------------------------------------------------------
// GPS time (spec: "GPSTIME11 v2" and the GPS time layer of "POINT14 v3"). Times are handled as
// 64-bit integers; up to four sequences with their own last time and delta absorb interleaved
// flight lines. A symbol `multi` says how the delta relates to the current sequence's delta.

constexpr std::uint32_t kGpsMulti = 500;
constexpr std::int32_t kGpsMultiMinus = -10;
constexpr std::uint32_t kGpsV2Unchanged = kGpsMulti - kGpsMultiMinus + 1;  // 511 (v2 only)
constexpr std::uint32_t kGpsV2CodeFull = kGpsMulti - kGpsMultiMinus + 2;   // 512
constexpr std::uint32_t kGpsV2Symbols = kGpsMulti - kGpsMultiMinus + 6;    // 516
constexpr std::uint32_t kGpsV3CodeFull = kGpsMulti - kGpsMultiMinus + 1;   // 511
constexpr std::uint32_t kGpsV3Symbols = kGpsMulti - kGpsMultiMinus + 5;    // 515
// A legitimate stream switches sequence at most once per point; more means corrupt data.
constexpr int kMaxSequenceSwitches = 8;

class GpsTimeDecoder {
public:
    GpsTimeDecoder(ArithmeticDecoder& decoder, bool layered)
            : decoder_(decoder),
              layered_(layered),
              multi_(layered ? kGpsV3Symbols : kGpsV2Symbols),
              zero_diff_(layered ? 5 : 6),
              ic_(decoder, 32, 9) {}

    void reset(std::uint64_t first) {
        last_ = next_ = 0;
        times_ = {first, 0, 0, 0};
        deltas_ = {0, 0, 0, 0};
        extremes_ = {0, 0, 0, 0};
    }
    std::uint64_t current() const { return times_[last_]; }

    // Decodes the next time; returns it as the raw 64 bits of the double.
    std::uint64_t decode() {
        for (int switches = 0; switches <= kMaxSequenceSwitches; ++switches)
            if (decode_step()) return times_[last_];
        throw Error(ExitCode::InvalidInput, "GPS time stream switches sequence repeatedly (corrupt data)");
    }

private:
    // One symbol; false when it only switched to another sequence (decode again there).
    bool decode_step() {
        if (deltas_[last_] == 0) {
            const std::uint32_t multi = decoder_.decode_symbol(zero_diff_);
            const std::uint32_t delta32 = layered_ ? 0 : 1, full = layered_ ? 1 : 2;
            if (!layered_ && multi == 0) return true;  // v2: unchanged
            if (multi == delta32) {
                deltas_[last_] = ic_.decompress(0, 0);
                times_[last_] += static_cast<std::uint64_t>(std::int64_t{deltas_[last_]});
                extremes_[last_] = 0;
            } else if (multi == full) {
                start_full_sequence();
            } else {
                last_ = (last_ + multi - full) & 3;
                return false;
            }
            return true;
        }
        const std::uint32_t multi = decoder_.decode_symbol(multi_);
        const std::uint32_t code_full = layered_ ? kGpsV3CodeFull : kGpsV2CodeFull;
        if (multi < kGpsV2Unchanged) {
            apply_multiplied_delta(multi);
        } else if (multi == code_full) {
            start_full_sequence();
        } else if (multi > code_full) {
            last_ = (last_ + multi - code_full) & 3;
            return false;
        }
        // v2: kGpsV2Unchanged leaves the time as it is.
        return true;
    }

    // multi 1: the delta repeats; 2..499: a multiple of it; 500: beyond; 0: unpredictable;
    // 501..510: -1..-10 times it. Each codes the difference to the predicted delta.
    void apply_multiplied_delta(std::uint32_t multi) {
        const std::int32_t delta = deltas_[last_];
        if (multi == 1) {
            times_[last_] += static_cast<std::uint64_t>(std::int64_t{ic_.decompress(delta, 1)});
            extremes_[last_] = 0;
            return;
        }
        std::int32_t diff;
        if (multi == 0) {
            diff = ic_.decompress(0, 7);
            note_extreme(diff);
        } else if (multi < kGpsMulti) {
            diff = ic_.decompress(wrapping_mul(static_cast<std::int32_t>(multi), delta), multi < 10 ? 2 : 3);
        } else if (multi == kGpsMulti) {
            diff = ic_.decompress(wrapping_mul(static_cast<std::int32_t>(kGpsMulti), delta), 4);
            note_extreme(diff);
        } else {
            const std::int32_t factor = static_cast<std::int32_t>(kGpsMulti) - static_cast<std::int32_t>(multi);
            if (factor > kGpsMultiMinus) {
                diff = ic_.decompress(wrapping_mul(factor, delta), 5);
            } else {
                diff = ic_.decompress(wrapping_mul(kGpsMultiMinus, delta), 6);
                note_extreme(diff);
            }
        }
        times_[last_] += static_cast<std::uint64_t>(std::int64_t{diff});
    }

    // After more than three deltas outside the predictable range the sequence adopts the new one.
    void note_extreme(std::int32_t diff) {
        if (++extremes_[last_] > 3) {
            deltas_[last_] = diff;
            extremes_[last_] = 0;
        }
    }

    // The delta overflows 32 bits: a new sequence with the upper half predicted, the lower raw.
    void start_full_sequence() {
        next_ = (next_ + 1) & 3;
        const auto high = static_cast<std::uint32_t>(ic_.decompress(static_cast<std::int32_t>(times_[last_] >> 32), 8));
        times_[next_] = (std::uint64_t{high} << 32) | decoder_.read_int();
        last_ = next_;
        deltas_[last_] = 0;
        extremes_[last_] = 0;
    }

    ArithmeticDecoder& decoder_;
    bool layered_;
    SymbolModel multi_, zero_diff_;
    IntegerDecompressor ic_;
    std::uint32_t last_ = 0, next_ = 0;
    std::array<std::uint64_t, 4> times_{};
    std::array<std::int32_t, 4> deltas_{};
    std::array<std::int32_t, 4> extremes_{};
};

// ---------------------------------------------------------------------------------------------
// RGB (spec: "RGB12 v2", same model in the RGB layer of "RGB14 v3"): a 7-bit symbol says which of
// the six bytes changed and whether the three channels changed alike; changed bytes are coded
// modulo 256 against the previous byte, green and blue predicted from red's change.

struct RgbModels {
    SymbolModel byte_used{128};
    std::array<SymbolModel, 6> diff{SymbolModel(256), SymbolModel(256), SymbolModel(256),
                                    SymbolModel(256), SymbolModel(256), SymbolModel(256)};
};

void decode_rgb(ArithmeticDecoder& dec, RgbModels& m, const std::array<std::uint16_t, 3>& last, std::array<std::uint16_t, 3>& out) {
    const std::uint32_t sym = dec.decode_symbol(m.byte_used);
    auto low = [](std::uint16_t v) { return static_cast<std::int32_t>(v & 0xFF); };
    auto high = [](std::uint16_t v) { return static_cast<std::int32_t>(v >> 8); };
    auto corr = [&](int i) { return static_cast<std::int32_t>(dec.decode_symbol(m.diff[static_cast<std::size_t>(i)])); };

    out[0] = (sym & 1) ? fold_u8(corr(0) + low(last[0])) : static_cast<std::uint16_t>(low(last[0]));
    out[0] |= static_cast<std::uint16_t>(((sym & 2) ? fold_u8(corr(1) + high(last[0])) : high(last[0])) << 8);
    if ((sym & 64) == 0) {  // grey: all channels equal red
        out[1] = out[2] = out[0];
        return;
    }
    std::int32_t diff = low(out[0]) - low(last[0]);
    out[1] = (sym & 4) ? fold_u8(corr(2) + clamp_u8(diff + low(last[1]))) : static_cast<std::uint16_t>(low(last[1]));
    if (sym & 16) {
        diff = (diff + low(out[1]) - low(last[1])) / 2;
        out[2] = fold_u8(corr(4) + clamp_u8(diff + low(last[2])));
    } else {
        out[2] = static_cast<std::uint16_t>(low(last[2]));
    }
    diff = high(out[0]) - high(last[0]);
    const std::int32_t g = (sym & 8) ? fold_u8(corr(3) + clamp_u8(diff + high(last[1]))) : high(last[1]);
    out[1] |= static_cast<std::uint16_t>(g << 8);
    std::int32_t b;
    if (sym & 32) {
        diff = (diff + high(out[1]) - high(last[1])) / 2;
        b = fold_u8(corr(5) + clamp_u8(diff + high(last[2])));
    } else {
        b = high(last[2]);
    }
    out[2] |= static_cast<std::uint16_t>(b << 8);
}

std::array<std::uint16_t, 3> load_rgb(const std::uint8_t* p) {
    return {load<std::uint16_t>(p), load<std::uint16_t>(p + 2), load<std::uint16_t>(p + 4)};
}
void store_rgb(std::uint8_t* p, const std::array<std::uint16_t, 3>& rgb) {
    for (int c = 0; c < 3; ++c) store<std::uint16_t>(p + 2 * c, rgb[static_cast<std::size_t>(c)]);
}

// ---------------------------------------------------------------------------------------------
// Point-wise items, version 2: all share the chunk's one arithmetic stream.

class PointwiseItem {
public:
    virtual ~PointwiseItem() = default;
    // The chunk's first point, stored raw, seeds the item's state.
    virtual void init(const std::uint8_t* first) = 0;
    virtual void decode(std::uint8_t* out) = 0;
};

// Return map m and return level l for (number of returns n, return number r), completed for
// invalid combinations (spec: "POINT10 v2").
constexpr std::uint8_t kReturnMap[8][8] = {{15, 14, 13, 12, 11, 10, 9, 8},  {14, 0, 1, 3, 6, 10, 10, 9},   {13, 1, 2, 4, 7, 11, 11, 10},
                                           {12, 3, 4, 5, 8, 12, 12, 11},    {11, 6, 7, 8, 9, 13, 13, 12},  {10, 10, 11, 12, 13, 14, 14, 13},
                                           {9, 10, 11, 12, 13, 14, 15, 14}, {8, 9, 10, 11, 12, 13, 14, 15}};
constexpr std::uint8_t kReturnLevel[8][8] = {{0, 1, 2, 3, 4, 5, 6, 7}, {1, 0, 1, 2, 3, 4, 5, 6}, {2, 1, 0, 1, 2, 3, 4, 5},
                                             {3, 2, 1, 0, 1, 2, 3, 4}, {4, 3, 2, 1, 0, 1, 2, 3}, {5, 4, 3, 2, 1, 0, 1, 2},
                                             {6, 5, 4, 3, 2, 1, 0, 1}, {7, 6, 5, 4, 3, 2, 1, 0}};

// The 20 bytes common to formats 0-5 (spec: "POINT10 v2").
class Point10Item final : public PointwiseItem {
public:
    explicit Point10Item(ArithmeticDecoder& dec)
            : dec_(dec),
              ic_intensity_(dec, 16, 4),
              ic_point_source_(dec, 16),
              ic_dx_(dec, 32, 2),
              ic_dy_(dec, 32, 22),
              ic_z_(dec, 32, 20) {}

    void init(const std::uint8_t* first) override {
        std::memcpy(last_.data(), first, 20);
        store<std::uint16_t>(last_.data() + 12, 0);  // the intensity prediction starts at 0
    }

    void decode(std::uint8_t* out) override {
        std::uint8_t* last = last_.data();
        const std::uint32_t changed = dec_.decode_symbol(changed_values_);
        if (changed & 32) last[14] = static_cast<std::uint8_t>(dec_.decode_symbol(bit_byte_[last[14]].get(256)));
        const std::uint32_t r = last[14] & 7, n = (last[14] >> 3) & 7;
        const std::uint32_t m = kReturnMap[n][r], l = kReturnLevel[n][r];
        if (changed != 0) {
            if (changed & 16) {
                last_intensity_[m] = static_cast<std::uint16_t>(ic_intensity_.decompress(last_intensity_[m], m < 3 ? m : 3));
            }
            store<std::uint16_t>(last + 12, last_intensity_[m]);
            if (changed & 8) last[15] = static_cast<std::uint8_t>(dec_.decode_symbol(classification_[last[15]].get(256)));
            if (changed & 4) {
                const std::uint32_t direction = (last[14] >> 6) & 1;
                const std::int32_t delta = static_cast<std::int32_t>(dec_.decode_symbol(scan_angle_[direction]));
                last[16] = fold_u8(delta + last[16]);
            }
            if (changed & 2) last[17] = static_cast<std::uint8_t>(dec_.decode_symbol(user_data_[last[17]].get(256)));
            if (changed & 1) {
                const auto source = ic_point_source_.decompress(load<std::uint16_t>(last + 18));
                store<std::uint16_t>(last + 18, static_cast<std::uint16_t>(source));
            }
        }
        // x and y: differences predicted by the median of the last five for this return map.
        const std::int32_t dx = ic_dx_.decompress(x_median_[m].get(), n == 1);
        store<std::int32_t>(last, wrapping_add(load<std::int32_t>(last), dx));
        x_median_[m].add(dx);
        std::uint32_t k_bits = ic_dx_.k();
        const std::int32_t dy = ic_dy_.decompress(y_median_[m].get(), (n == 1) + (k_bits < 20 ? zero_bit_0(k_bits) : 20));
        store<std::int32_t>(last + 4, wrapping_add(load<std::int32_t>(last + 4), dy));
        y_median_[m].add(dy);
        // z: predicted by the last z at the same return level.
        k_bits = (ic_dx_.k() + ic_dy_.k()) / 2;
        last_height_[l] = ic_z_.decompress(last_height_[l], (n == 1) + (k_bits < 18 ? zero_bit_0(k_bits) : 18));
        store<std::int32_t>(last + 8, last_height_[l]);
        std::memcpy(out, last, 20);
    }

private:
    ArithmeticDecoder& dec_;
    std::array<std::uint8_t, 20> last_{};
    SymbolModel changed_values_{64};
    std::array<LazyModel, 256> bit_byte_, classification_, user_data_;
    std::array<SymbolModel, 2> scan_angle_{SymbolModel(256), SymbolModel(256)};
    IntegerDecompressor ic_intensity_, ic_point_source_, ic_dx_, ic_dy_, ic_z_;
    std::array<std::uint16_t, 16> last_intensity_{};
    std::array<StreamingMedian5, 16> x_median_{}, y_median_{};
    std::array<std::int32_t, 8> last_height_{};
};

class GpsTime11Item final : public PointwiseItem {
public:
    explicit GpsTime11Item(ArithmeticDecoder& dec) : gps_(dec, false) {}
    void init(const std::uint8_t* first) override { gps_.reset(load<std::uint64_t>(first)); }
    void decode(std::uint8_t* out) override { store<std::uint64_t>(out, gps_.decode()); }

private:
    GpsTimeDecoder gps_;
};

class Rgb12Item final : public PointwiseItem {
public:
    explicit Rgb12Item(ArithmeticDecoder& dec) : dec_(dec) {}
    void init(const std::uint8_t* first) override { last_ = load_rgb(first); }
    void decode(std::uint8_t* out) override {
        std::array<std::uint16_t, 3> rgb{};
        decode_rgb(dec_, models_, last_, rgb);
        last_ = rgb;
        store_rgb(out, rgb);
    }

private:
    ArithmeticDecoder& dec_;
    RgbModels models_;
    std::array<std::uint16_t, 3> last_{};
};

// Extra bytes: each byte coded modulo 256 against the previous point's byte (spec: "BYTE v2").
class ByteItem final : public PointwiseItem {
public:
    ByteItem(ArithmeticDecoder& dec, std::size_t count) : dec_(dec), last_(count) {
        models_.reserve(count);
        for (std::size_t i = 0; i < count; ++i) models_.emplace_back(256);
    }
    void init(const std::uint8_t* first) override { std::memcpy(last_.data(), first, last_.size()); }
    void decode(std::uint8_t* out) override {
        for (std::size_t i = 0; i < last_.size(); ++i)
            last_[i] = fold_u8(last_[i] + static_cast<std::int32_t>(dec_.decode_symbol(models_[i])));
        std::memcpy(out, last_.data(), last_.size());
    }

private:
    ArithmeticDecoder& dec_;
    std::vector<std::uint8_t> last_;
    std::vector<SymbolModel> models_;
};

// ---------------------------------------------------------------------------------------------
// Layered items, version 3: each item reads its layer sizes, then its layers, each with its own
// arithmetic stream. Four contexts (one per scanner channel) hold separate models and previous
// values; POINT14 decodes the channel and passes it to the other items.

class LayeredItem {
public:
    virtual ~LayeredItem() = default;
    virtual std::size_t layer_count() const = 0;
    // `layers[i]` is layer i's bytes (empty when the layer is unchanged in this chunk or not
    // wanted, in which case the field keeps the first point's value).
    virtual void init(const std::uint8_t* first, const std::vector<std::span<const std::uint8_t>>& layers, std::uint32_t context) = 0;
    virtual void decode(std::uint8_t* out, std::uint32_t& context) = 0;
    // Largest read-ahead past the end of any layer stream.
    virtual std::size_t overrun() const = 0;
};

std::size_t max_overrun(std::span<const ArithmeticDecoder> decoders) {
    std::size_t worst = 0;
    for (const ArithmeticDecoder& d : decoders) worst = std::max(worst, d.overrun());
    return worst;
}

// The fields of formats 6-10's first 30 bytes (spec: "POINT14 v3").
struct Point14 {
    std::int32_t x = 0, y = 0, z = 0;
    std::uint16_t intensity = 0;
    std::uint8_t return_number = 0, number_of_returns = 0;
    std::uint8_t class_flags = 0, scanner_channel = 0, scan_direction = 0, edge = 0;
    std::uint8_t classification = 0, user_data = 0;
    std::int16_t scan_angle = 0;
    std::uint16_t point_source = 0;
    std::uint64_t gps_time = 0;
    bool gps_time_change = false;  // whether this point's time differed from its predecessor's

    static Point14 load_from(const std::uint8_t* p) {
        Point14 q;
        q.x = load<std::int32_t>(p);
        q.y = load<std::int32_t>(p + 4);
        q.z = load<std::int32_t>(p + 8);
        q.intensity = load<std::uint16_t>(p + 12);
        q.return_number = p[14] & 0x0F;
        q.number_of_returns = p[14] >> 4;
        q.class_flags = p[15] & 0x0F;
        q.scanner_channel = (p[15] >> 4) & 3;
        q.scan_direction = (p[15] >> 6) & 1;
        q.edge = p[15] >> 7;
        q.classification = p[16];
        q.user_data = p[17];
        q.scan_angle = load<std::int16_t>(p + 18);
        q.point_source = load<std::uint16_t>(p + 20);
        q.gps_time = load<std::uint64_t>(p + 22);
        return q;
    }
    void store_to(std::uint8_t* p) const {
        store<std::int32_t>(p, x);
        store<std::int32_t>(p + 4, y);
        store<std::int32_t>(p + 8, z);
        store<std::uint16_t>(p + 12, intensity);
        p[14] = static_cast<std::uint8_t>(return_number | (number_of_returns << 4));
        p[15] = static_cast<std::uint8_t>(class_flags | (scanner_channel << 4) | (scan_direction << 6) | (edge << 7));
        p[16] = classification;
        p[17] = user_data;
        store<std::int16_t>(p + 18, scan_angle);
        store<std::uint16_t>(p + 20, point_source);
        store<std::uint64_t>(p + 22, gps_time);
    }
};

// 6 return-map contexts and 8 return-level contexts for 4-bit (n, r) (spec: "number_return_map_6ctx",
// "number_return_level_8ctx").
constexpr std::uint8_t kReturnMap6[16][16] = {
        {0, 1, 2, 3, 4, 5, 3, 4, 4, 5, 5, 5, 5, 5, 5, 5}, {1, 0, 1, 3, 3, 3, 3, 3, 3, 3, 3, 3, 3, 3, 3, 3},
        {2, 1, 2, 4, 4, 4, 4, 4, 4, 4, 4, 3, 3, 3, 3, 3}, {3, 3, 4, 5, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4},
        {4, 3, 4, 4, 5, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4}, {5, 3, 4, 4, 4, 5, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4},
        {3, 3, 4, 4, 4, 4, 5, 4, 4, 4, 4, 4, 4, 4, 4, 4}, {4, 3, 4, 4, 4, 4, 4, 5, 4, 4, 4, 4, 4, 4, 4, 4},
        {4, 3, 4, 4, 4, 4, 4, 4, 5, 4, 4, 4, 4, 4, 4, 4}, {5, 3, 4, 4, 4, 4, 4, 4, 4, 5, 4, 4, 4, 4, 4, 4},
        {5, 3, 4, 4, 4, 4, 4, 4, 4, 4, 5, 4, 4, 4, 4, 4}, {5, 3, 3, 4, 4, 4, 4, 4, 4, 4, 4, 5, 5, 4, 4, 4},
        {5, 3, 3, 4, 4, 4, 4, 4, 4, 4, 4, 5, 5, 5, 4, 4}, {5, 3, 3, 4, 4, 4, 4, 4, 4, 4, 4, 4, 5, 5, 5, 4},
        {5, 3, 3, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 5, 5, 5}, {5, 3, 3, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 5, 5}};

std::uint8_t return_level_8(std::uint32_t n, std::uint32_t r) {
    // |n - r| capped at 7: the table of the spec written as the rule it encodes.
    const std::uint32_t d = n > r ? n - r : r - n;
    return static_cast<std::uint8_t>(std::min<std::uint32_t>(d, 7));
}

enum Point14Layer : std::size_t { XY, Z, Classification, Flags, Intensity, ScanAngle, UserData, PointSource, GpsTime, kPoint14Layers };

class Point14Item final : public LayeredItem {
public:
    explicit Point14Item(const LayerSelection& selection) {
        wanted_ = {true,
                   selection.z,
                   selection.classification,
                   selection.flags,
                   selection.intensity,
                   selection.scan_angle,
                   selection.user_data,
                   selection.point_source,
                   selection.gps_time};
    }
    std::size_t layer_count() const override { return kPoint14Layers; }
    std::size_t overrun() const override { return max_overrun(decoders_); }

    void init(const std::uint8_t* first, const std::vector<std::span<const std::uint8_t>>& layers, std::uint32_t) override {
        for (std::size_t i = 0; i < kPoint14Layers; ++i) {
            changed_[i] = wanted_[i] && !layers[i].empty();
            // The XY layer is always decoded (an empty one then reads as zeros and is reported).
            if (changed_[i] || i == XY) decoders_[i].init(layers[i].data(), layers[i].size());
        }
        const Point14 point = Point14::load_from(first);
        for (auto& c : contexts_) c.reset();
        current_ = point.scanner_channel;
        create_context(current_, point);
    }

    void decode(std::uint8_t* out, std::uint32_t& context) override {
        Context* c = contexts_[current_].get();
        ArithmeticDecoder& xy = decoders_[XY];
        // Context of the previous point's return: single / first / last / intermediate, and
        // whether its GPS time had changed.
        std::uint32_t lpr = (c->last.return_number == 1 ? 1 : 0) + (c->last.return_number >= c->last.number_of_returns ? 2 : 0) +
                            (c->last.gps_time_change ? 4 : 0);
        const std::uint32_t changed = xy.decode_symbol(c->changed_values[lpr]);
        if (changed & (1 << 6)) {  // another scanner channel: switch context (spec: "scanner channel")
            const std::uint32_t step = xy.decode_symbol(c->scanner_channel);
            const std::uint32_t channel = (current_ + step + 1) % 4;
            if (!contexts_[channel]) create_context(channel, c->last);
            current_ = channel;
            c = contexts_[current_].get();
            c->last.scanner_channel = static_cast<std::uint8_t>(channel);
        }
        context = current_;
        Point14& last = c->last;
        const bool point_source_change = changed & (1 << 5);
        const bool gps_time_change = changed & (1 << 4);
        const bool scan_angle_change = changed & (1 << 3);

        const std::uint32_t last_n = last.number_of_returns, last_r = last.return_number;
        std::uint32_t n = last_n;
        if (changed & (1 << 2)) {
            n = xy.decode_symbol(c->number_of_returns[last_n].get(16));
            last.number_of_returns = static_cast<std::uint8_t>(n);
        }
        std::uint32_t r = last_r;
        switch (changed & 3) {
            case 0:
                break;
            case 1:
                r = (last_r + 1) % 16;
                break;
            case 2:
                r = (last_r + 15) % 16;
                break;
            default:
                if (gps_time_change)
                    r = xy.decode_symbol(c->return_number[last_r].get(16));
                else
                    r = (last_r + xy.decode_symbol(c->return_number_gps_same) + 2) % 16;
        }
        last.return_number = static_cast<std::uint8_t>(r);

        const std::uint32_t m = kReturnMap6[n][r], l = return_level_8(n, r);
        const std::uint32_t cpr = (r == 1 ? 2 : 0) + (r >= n ? 1 : 0);  // current point: single 3, first 2, last 1
        const std::size_t median = (m << 1) | (gps_time_change ? 1 : 0);

        const std::int32_t dx = c->ic_dx.decompress(c->x_median[median].get(), n == 1);
        last.x = wrapping_add(last.x, dx);
        c->x_median[median].add(dx);
        std::uint32_t k_bits = c->ic_dx.k();
        const std::int32_t dy = c->ic_dy.decompress(c->y_median[median].get(), (n == 1) + (k_bits < 20 ? zero_bit_0(k_bits) : 20));
        last.y = wrapping_add(last.y, dy);
        c->y_median[median].add(dy);

        if (changed_[Z]) {
            k_bits = (c->ic_dx.k() + c->ic_dy.k()) / 2;
            last.z = c->ic_z.decompress(c->last_z[l], (n == 1) + (k_bits < 18 ? zero_bit_0(k_bits) : 18));
            c->last_z[l] = last.z;
        }
        if (changed_[Classification]) {
            const std::size_t ccc = ((last.classification & 0x1Fu) << 1) + (cpr == 3 ? 1 : 0);
            last.classification = static_cast<std::uint8_t>(decoders_[Classification].decode_symbol(c->classification[ccc].get(256)));
        }
        if (changed_[Flags]) {
            const std::size_t previous = (last.edge << 5) | (last.scan_direction << 4) | last.class_flags;
            const std::uint32_t flags = decoders_[Flags].decode_symbol(c->flags[previous].get(64));
            last.edge = (flags >> 5) & 1;
            last.scan_direction = (flags >> 4) & 1;
            last.class_flags = flags & 0x0F;
        }
        if (changed_[Intensity]) {
            const std::size_t slot = (cpr << 1) | (gps_time_change ? 1 : 0);
            last.intensity = static_cast<std::uint16_t>(c->ic_intensity.decompress(c->last_intensity[slot], cpr));
            c->last_intensity[slot] = last.intensity;
        }
        if (changed_[ScanAngle] && scan_angle_change)
            last.scan_angle = static_cast<std::int16_t>(c->ic_scan_angle.decompress(last.scan_angle, gps_time_change));
        if (changed_[UserData])
            last.user_data = static_cast<std::uint8_t>(decoders_[UserData].decode_symbol(c->user_data[last.user_data / 4].get(256)));
        if (changed_[PointSource] && point_source_change)
            last.point_source = static_cast<std::uint16_t>(c->ic_point_source.decompress(last.point_source));
        if (changed_[GpsTime] && gps_time_change) last.gps_time = c->gps.decode();

        last.store_to(out);
        last.gps_time_change = gps_time_change;
    }

private:
    struct Context {
        explicit Context(std::array<ArithmeticDecoder, kPoint14Layers>& d)
                : ic_dx(d[XY], 32, 2),
                  ic_dy(d[XY], 32, 22),
                  ic_z(d[Z], 32, 20),
                  ic_intensity(d[Intensity], 16, 4),
                  ic_scan_angle(d[ScanAngle], 16, 2),
                  ic_point_source(d[PointSource], 16),
                  gps(d[GpsTime], true) {
            changed_values.reserve(8);
            for (int i = 0; i < 8; ++i) changed_values.emplace_back(128);
        }
        Point14 last;
        std::vector<SymbolModel> changed_values;
        SymbolModel scanner_channel{3};
        std::array<LazyModel, 16> number_of_returns, return_number;
        SymbolModel return_number_gps_same{13};
        IntegerDecompressor ic_dx, ic_dy, ic_z, ic_intensity, ic_scan_angle, ic_point_source;
        std::array<LazyModel, 64> classification, flags, user_data;
        std::array<StreamingMedian5, 12> x_median{}, y_median{};
        std::array<std::int32_t, 8> last_z{};
        std::array<std::uint16_t, 8> last_intensity{};
        GpsTimeDecoder gps;
    };

    // A channel seen for the first time in the chunk starts from the previous point (of any
    // channel), or from the raw first point.
    void create_context(std::uint32_t channel, const Point14& seed) {
        auto c = std::make_unique<Context>(decoders_);
        c->last = seed;
        c->last.gps_time_change = false;
        c->last_z.fill(seed.z);
        c->last_intensity.fill(seed.intensity);
        c->gps.reset(seed.gps_time);
        contexts_[channel] = std::move(c);
    }

    std::array<bool, kPoint14Layers> wanted_{}, changed_{};
    std::array<ArithmeticDecoder, kPoint14Layers> decoders_;
    std::array<std::unique_ptr<Context>, 4> contexts_;
    std::uint32_t current_ = 0;
};

// RGB14 (one layer) and RGBNIR14 (RGB layer, then NIR layer), per scanner channel.
class Rgb14Item final : public LayeredItem {
public:
    Rgb14Item(bool nir, const LayerSelection& selection) : nir_(nir), want_rgb_(selection.rgb), want_nir_(selection.nir) {}
    std::size_t layer_count() const override { return nir_ ? 2 : 1; }
    std::size_t overrun() const override { return max_overrun(decoders_); }

    void init(const std::uint8_t* first, const std::vector<std::span<const std::uint8_t>>& layers, std::uint32_t context) override {
        changed_rgb_ = want_rgb_ && !layers[0].empty();
        if (changed_rgb_) decoders_[0].init(layers[0].data(), layers[0].size());
        changed_nir_ = nir_ && want_nir_ && !layers[1].empty();
        if (changed_nir_) decoders_[1].init(layers[1].data(), layers[1].size());
        for (auto& c : contexts_) c.reset();
        current_ = context;
        Last seed{load_rgb(first), nir_ ? load<std::uint16_t>(first + 6) : std::uint16_t{0}};
        create_context(current_, seed);
    }

    void decode(std::uint8_t* out, std::uint32_t& context) override {
        Last* last = &contexts_[current_]->last;
        switch_context(context, last);
        Context& c = *contexts_[current_];
        if (changed_rgb_) {
            std::array<std::uint16_t, 3> rgb{};
            decode_rgb(decoders_[0], c.rgb, last->rgb, rgb);
            last->rgb = rgb;
        }
        store_rgb(out, last->rgb);
        if (!nir_) return;
        if (changed_nir_) {
            // NIR: which of its two bytes changed, then each changed byte modulo 256.
            const std::uint32_t used = decoders_[1].decode_symbol(c.nir_used);
            const std::int32_t low = last->nir & 0xFF, high = last->nir >> 8;
            const std::int32_t new_low =
                    (used & 1) ? fold_u8(static_cast<std::int32_t>(decoders_[1].decode_symbol(c.nir_diff[0])) + low) : low;
            const std::int32_t new_high =
                    (used & 2) ? fold_u8(static_cast<std::int32_t>(decoders_[1].decode_symbol(c.nir_diff[1])) + high) : high;
            last->nir = static_cast<std::uint16_t>(new_low | (new_high << 8));
        }
        store<std::uint16_t>(out + 6, last->nir);
    }

private:
    struct Last {
        std::array<std::uint16_t, 3> rgb;
        std::uint16_t nir;
    };
    struct Context {
        Last last;
        RgbModels rgb;
        SymbolModel nir_used{4};
        std::array<SymbolModel, 2> nir_diff{SymbolModel(256), SymbolModel(256)};
    };
    void create_context(std::uint32_t channel, const Last& seed) {
        contexts_[channel] = std::make_unique<Context>();
        contexts_[channel]->last = seed;
    }
    // The channel's models always follow the point's channel, but its previous values only when
    // the channel is new in the chunk (seeded from the previous point); on a return to a channel
    // seen before, the reference encoder predicts from the previous point's values, so the
    // decoder must too.
    void switch_context(std::uint32_t context, Last*& last) {
        if (context == current_) return;
        current_ = context;
        if (!contexts_[current_]) {
            create_context(current_, *last);
            last = &contexts_[current_]->last;
        }
    }

    bool nir_, want_rgb_, want_nir_;
    bool changed_rgb_ = false, changed_nir_ = false;
    std::array<ArithmeticDecoder, 2> decoders_;
    std::array<std::unique_ptr<Context>, 4> contexts_;
    std::uint32_t current_ = 0;
};

// Extra bytes, one layer per byte (spec: "BYTE14 v3").
class Byte14Item final : public LayeredItem {
public:
    Byte14Item(std::size_t count, const LayerSelection& selection)
            : count_(count), wanted_(selection.extra_bytes), decoders_(count), changed_(count, false) {}
    std::size_t layer_count() const override { return count_; }
    std::size_t overrun() const override { return max_overrun(decoders_); }

    void init(const std::uint8_t* first, const std::vector<std::span<const std::uint8_t>>& layers, std::uint32_t context) override {
        for (std::size_t i = 0; i < count_; ++i) {
            changed_[i] = wanted_ && !layers[i].empty();
            if (changed_[i]) decoders_[i].init(layers[i].data(), layers[i].size());
        }
        for (auto& c : contexts_) c.reset();
        current_ = context;
        create_context(current_, std::vector<std::uint8_t>(first, first + count_));
    }

    void decode(std::uint8_t* out, std::uint32_t& context) override {
        // Same context rule as RGB14: models of the point's channel, previous values of the
        // previous point unless the channel is new in the chunk.
        std::vector<std::uint8_t>* last = &contexts_[current_]->last;
        if (context != current_) {
            current_ = context;
            if (!contexts_[current_]) {
                create_context(current_, *last);
                last = &contexts_[current_]->last;
            }
        }
        Context& c = *contexts_[current_];
        for (std::size_t i = 0; i < count_; ++i)
            if (changed_[i]) (*last)[i] = fold_u8((*last)[i] + static_cast<std::int32_t>(decoders_[i].decode_symbol(c.models[i])));
        std::memcpy(out, last->data(), count_);
    }

private:
    struct Context {
        std::vector<std::uint8_t> last;
        std::vector<SymbolModel> models;
    };
    void create_context(std::uint32_t channel, std::vector<std::uint8_t> seed) {
        auto c = std::make_unique<Context>();
        c->last = std::move(seed);
        c->models.reserve(count_);
        for (std::size_t i = 0; i < count_; ++i) c->models.emplace_back(256);
        contexts_[channel] = std::move(c);
    }

    std::size_t count_;
    bool wanted_;
    std::vector<ArithmeticDecoder> decoders_;
    std::vector<bool> changed_;
    std::array<std::unique_ptr<Context>, 4> contexts_;
    std::uint32_t current_ = 0;
};

// ---------------------------------------------------------------------------------------------
// VLR

constexpr std::size_t kVlrFixedSize = 34;
constexpr std::size_t kItemRecordSize = 6;

const char* item_name(ItemType type) {
    switch (type) {
        case ItemType::Byte:
            return "BYTE";
        case ItemType::Point10:
            return "POINT10";
        case ItemType::GpsTime11:
            return "GPSTIME11";
        case ItemType::Rgb12:
            return "RGB12";
        case ItemType::WavePacket13:
            return "WAVEPACKET13";
        case ItemType::Point14:
            return "POINT14";
        case ItemType::Rgb14:
            return "RGB14";
        case ItemType::RgbNir14:
            return "RGBNIR14";
        case ItemType::WavePacket14:
            return "WAVEPACKET14";
        case ItemType::Byte14:
            return "BYTE14";
    }
    return "unknown";
}

std::string item_label(const Item& item) {
    const auto type = static_cast<std::uint16_t>(item.type);
    const bool known = type == 0 || (type >= 6 && type <= 14);
    return std::string(known ? item_name(item.type) : ("type " + std::to_string(type)).c_str()) + " v" + std::to_string(item.version) +
           " (" + std::to_string(item.size) + " bytes)";
}

// The items LASzip writes for a point format, in order, without the extra-bytes item.
std::vector<Item> expected_items(int format) {
    const bool layered = format >= 6;
    std::vector<Item> items;
    items.push_back(layered ? Item{ItemType::Point14, 30, 3} : Item{ItemType::Point10, 20, 2});
    const bool gps = format == 1 || format >= 3;
    const bool rgb = format == 2 || format == 3 || format == 5 || format == 7;
    const bool rgbnir = format == 8 || format == 10;
    const bool waves = format == 4 || format == 5 || format == 9 || format == 10;
    if (gps && !layered) items.push_back({ItemType::GpsTime11, 8, 2});
    if (rgb) items.push_back(layered ? Item{ItemType::Rgb14, 6, 3} : Item{ItemType::Rgb12, 6, 2});
    if (rgbnir) items.push_back({ItemType::RgbNir14, 8, 3});
    if (waves) items.push_back(layered ? Item{ItemType::WavePacket14, 29, 3} : Item{ItemType::WavePacket13, 29, 1});
    return items;
}

std::string describe_items(const std::vector<Item>& items) {
    std::string text;
    for (const Item& item : items) text += (text.empty() ? "" : ", ") + item_label(item);
    return text;
}

}  // namespace

LaszipVlr parse_laszip_vlr(std::span<const std::uint8_t> data, int point_format, std::uint16_t record_length, const std::string& file) {
    auto fail = [&](const std::string& what) { throw Error::input(file, "LASzip VLR: " + what); };
    if (data.size() < kVlrFixedSize) fail(std::to_string(data.size()) + " bytes, expected at least 34");
    const std::uint8_t* p = data.data();
    LaszipVlr vlr;
    vlr.compressor = load<std::uint16_t>(p);
    vlr.coder = load<std::uint16_t>(p + 2);
    vlr.version_major = p[4];
    vlr.version_minor = p[5];
    vlr.version_revision = load<std::uint16_t>(p + 6);
    vlr.options = load<std::uint32_t>(p + 8);
    vlr.chunk_size = load<std::uint32_t>(p + 12);
    const std::size_t item_count = load<std::uint16_t>(p + 32);
    if (data.size() < kVlrFixedSize + item_count * kItemRecordSize)
        fail("declares " + std::to_string(item_count) + " items but holds " + std::to_string(data.size()) + " bytes");
    for (std::size_t i = 0; i < item_count; ++i) {
        const std::uint8_t* q = p + kVlrFixedSize + i * kItemRecordSize;
        vlr.items.push_back({static_cast<ItemType>(load<std::uint16_t>(q)), load<std::uint16_t>(q + 2), load<std::uint16_t>(q + 4)});
    }
    if (vlr.coder != 0) fail("coder " + std::to_string(vlr.coder) + " is not the arithmetic coder (0)");
    if (vlr.compressor < 1 || vlr.compressor > 3)
        fail("compressor " + std::to_string(vlr.compressor) + ", expected 1 (point-wise), 2 (chunked) or 3 (layered)");
    if (point_format >= 6 && vlr.compressor != 3)
        fail("point format " + std::to_string(point_format) + " needs the layered compressor (3), the file declares " +
             std::to_string(vlr.compressor));
    if (point_format < 6 && vlr.compressor == 3)
        fail("point format " + std::to_string(point_format) + " is not compressed with the layered compressor (3)");
    if (vlr.chunk_size == 0) fail("chunk size is 0");

    // The items must be exactly those of the point format, then optional extra bytes.
    const std::vector<Item> expected = expected_items(point_format);
    std::vector<Item> standard(vlr.items.begin(),
                               vlr.items.begin() + static_cast<std::ptrdiff_t>(std::min(expected.size(), vlr.items.size())));
    bool matches = standard.size() == expected.size();
    for (std::size_t i = 0; matches && i < expected.size(); ++i)
        matches = standard[i].type == expected[i].type && standard[i].size == expected[i].size;
    const std::size_t extra_items = vlr.items.size() - standard.size();
    const ItemType extra_type = point_format >= 6 ? ItemType::Byte14 : ItemType::Byte;
    if (matches && extra_items > 1) matches = false;
    if (matches && extra_items == 1 && vlr.items.back().type != extra_type) matches = false;
    if (!matches)
        fail("items [" + describe_items(vlr.items) + "] do not match point format " + std::to_string(point_format) + ", which needs [" +
             describe_items(expected) + "] plus optional " + item_name(extra_type));
    std::size_t total = 0;
    for (const Item& item : vlr.items) {
        total += item.size;
        if (item.type == ItemType::WavePacket13 || item.type == ItemType::WavePacket14)
            fail("waveform packets (" + item_label(item) + ") are not supported");
        const std::uint16_t wanted_version = point_format >= 6 ? 3 : 2;
        if (item.version != wanted_version)
            fail(item_label(item) + ": only version " + std::to_string(wanted_version) + " is supported for point format " +
                 std::to_string(point_format) + (item.version < wanted_version ? " (written by a LASzip older than 2.0?)" : ""));
    }
    if (total != record_length)
        fail("items [" + describe_items(vlr.items) + "] add up to " + std::to_string(total) +
             " bytes, but the header's point record length is " + std::to_string(record_length));
    return vlr;
}

namespace {

[[noreturn]] void chunk_fail(const std::string& file, std::size_t chunk, const std::string& what) {
    throw Error::input(file, "LAZ chunk " + std::to_string(chunk) + ": " + what);
}

void check_overrun(std::size_t overrun, const std::string& file, std::size_t chunk) {
    if (overrun > kOverrunSlack)
        chunk_fail(file, chunk,
                   "compressed data ends " + std::to_string(overrun) + " bytes before its points do (truncated or corrupt chunk)");
}

void decode_pointwise_chunk(const LaszipVlr& vlr, std::uint16_t record_length, std::span<const std::uint8_t> data, std::size_t count,
                            std::uint8_t* out, const std::string& file, std::size_t chunk) {
    if (data.size() < record_length)
        chunk_fail(file, chunk,
                   std::to_string(data.size()) + " bytes cannot hold its first point (" + std::to_string(record_length) +
                           " bytes stored raw)");
    // The first point is stored raw; the arithmetic stream follows it.
    std::memcpy(out, data.data(), record_length);
    ArithmeticDecoder decoder;
    std::vector<std::unique_ptr<PointwiseItem>> items;
    std::vector<std::size_t> offsets;
    std::size_t offset = 0;
    for (const Item& item : vlr.items) {
        switch (item.type) {
            case ItemType::Point10:
                items.push_back(std::make_unique<Point10Item>(decoder));
                break;
            case ItemType::GpsTime11:
                items.push_back(std::make_unique<GpsTime11Item>(decoder));
                break;
            case ItemType::Rgb12:
                items.push_back(std::make_unique<Rgb12Item>(decoder));
                break;
            default:
                items.push_back(std::make_unique<ByteItem>(decoder, item.size));
                break;
        }
        items.back()->init(out + offset);
        offsets.push_back(offset);
        offset += item.size;
    }
    if (count <= 1) return;
    decoder.init(data.data() + record_length, data.size() - record_length);
    for (std::size_t p = 1; p < count; ++p) {
        std::uint8_t* record = out + p * record_length;
        for (std::size_t i = 0; i < items.size(); ++i) items[i]->decode(record + offsets[i]);
    }
    check_overrun(decoder.overrun(), file, chunk);
}

void decode_layered_chunk(const LaszipVlr& vlr, std::uint16_t record_length, std::span<const std::uint8_t> data, std::size_t count,
                          std::uint8_t* out, const LayerSelection& selection, const std::string& file, std::size_t chunk) {
    if (data.size() < record_length)
        chunk_fail(file, chunk,
                   std::to_string(data.size()) + " bytes cannot hold its first point (" + std::to_string(record_length) +
                           " bytes stored raw)");
    std::memcpy(out, data.data(), record_length);
    if (count <= 1) return;

    std::vector<std::unique_ptr<LayeredItem>> items;
    for (const Item& item : vlr.items) {
        switch (item.type) {
            case ItemType::Point14:
                items.push_back(std::make_unique<Point14Item>(selection));
                break;
            case ItemType::Rgb14:
                items.push_back(std::make_unique<Rgb14Item>(false, selection));
                break;
            case ItemType::RgbNir14:
                items.push_back(std::make_unique<Rgb14Item>(true, selection));
                break;
            default:
                items.push_back(std::make_unique<Byte14Item>(item.size, selection));
                break;
        }
    }
    // After the raw point: the point count (4 bytes), every layer's byte count (4 bytes each, in
    // item order), then the layers in the same order (spec: "Chunk Layout").
    std::size_t pos = record_length + 4;
    std::size_t layer_total = 0;
    for (const auto& item : items) layer_total += item->layer_count();
    if (data.size() < pos + 4 * layer_total)
        chunk_fail(file, chunk, "ends inside its layer table (" + std::to_string(data.size()) + " bytes)");
    std::vector<std::uint32_t> sizes(layer_total);
    for (std::uint32_t& size : sizes) {
        size = load<std::uint32_t>(data.data() + pos);
        pos += 4;
    }
    std::size_t layer = 0;
    std::uint32_t context = out[15] >> 4 & 3;  // the first point's scanner channel
    std::vector<std::size_t> offsets;
    std::size_t offset = 0;
    for (std::size_t i = 0; i < items.size(); ++i) {
        std::vector<std::span<const std::uint8_t>> layers;
        for (std::size_t k = 0; k < items[i]->layer_count(); ++k, ++layer) {
            if (sizes[layer] > data.size() - pos)
                chunk_fail(file, chunk,
                           "layer " + std::to_string(layer + 1) + " declares " + std::to_string(sizes[layer]) + " bytes, only " +
                                   std::to_string(data.size() - pos) + " remain in the chunk");
            layers.push_back(data.subspan(pos, sizes[layer]));
            pos += sizes[layer];
        }
        items[i]->init(out + offset, layers, context);
        offsets.push_back(offset);
        offset += vlr.items[i].size;
    }
    for (std::size_t p = 1; p < count; ++p) {
        std::uint8_t* record = out + p * record_length;
        for (std::size_t i = 0; i < items.size(); ++i) items[i]->decode(record + offsets[i], context);
    }
    for (const auto& item : items) check_overrun(item->overrun(), file, chunk);
}

}  // namespace

void decode_chunk(const LaszipVlr& vlr, std::uint16_t record_length, std::span<const std::uint8_t> data, std::size_t count,
                  std::uint8_t* out, const LayerSelection& selection, const std::string& file, std::size_t chunk_index) {
    if (count == 0) return;
    try {
        if (vlr.compressor == 3)
            decode_layered_chunk(vlr, record_length, data, count, out, selection, file, chunk_index);
        else
            decode_pointwise_chunk(vlr, record_length, data, count, out, file, chunk_index);
    } catch (const Error& e) {
        if (e.code() != ExitCode::InvalidInput || std::string_view(e.what()).starts_with(file)) throw;
        chunk_fail(file, chunk_index, e.what());  // errors raised inside the models lack the file name
    }
}

}  // namespace treelobes::laz
