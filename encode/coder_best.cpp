#include "encode/coder_best.hpp"

#include "core/error.hpp"
#include "encode/bitstream.hpp"
#include "encode/coder_ic.hpp"
#include "core/range_coder.hpp"

#include <zlib.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <memory>

namespace treelobes::encode {

namespace {

// ---- Shared plumbing: one modelling routine serves the encoder and the decoder ---------------

// IO policies: `bit(model, b)` codes b (encoder) or returns the decoded bit (decoder, b ignored).
struct Encoding {
    static constexpr bool kEncoding = true;
    RangeEncoder rc;
    bool bit(BitModel& m, bool b) {
        rc.encode(m, b);
        return b;
    }
    std::uint64_t direct(std::uint64_t v, unsigned n) {
        rc.encode_direct(v, n);
        return v;
    }
    [[noreturn]] void fail(const char* what) { throw Error(ExitCode::Internal, what); }
};

struct Decoding {
    static constexpr bool kEncoding = false;
    RangeDecoder rc;
    [[gnu::always_inline]] bool bit(BitModel& m, bool) { return rc.decode(m); }
    std::uint64_t direct(std::uint64_t, unsigned n) { return rc.decode_direct(n); }
    [[noreturn]] void fail(const char* what) { rc.fail(what); }
};

// Adaptive Exp-Golomb: the bit width k of v in unary (k = 0 is v = 0, so the first decision is
// the "is zero" flag), then the bits below the leading one — as a bit tree for k <= 6, where
// the distribution within a width still matters, and as plain bits above.
struct UIntModel {
    static constexpr unsigned kUnary = 24, kTreeWidth = 6;
    std::array<BitModel, kUnary> unary;
    std::array<BitModel, 62> tree;  // widths 2..6: offsets 2^(k-1) - 2
};

constexpr unsigned kMaxWidth = 62;

template <class IO>
[[gnu::always_inline]] inline std::uint64_t code_uint(IO& io, UIntModel& m, std::uint64_t v) {
    const unsigned width = IO::kEncoding ? bit_width64(v) : 0;
    if (IO::kEncoding && width > kMaxWidth) io.fail("value too large for the arithmetic coder");
    unsigned k = 0;
    while (io.bit(m.unary[std::min(k, UIntModel::kUnary - 1)], k < width)) {
        if (++k > kMaxWidth) io.fail("corrupt integer code");
    }
    if (k <= 1) return k;
    const unsigned low_bits = k - 1;
    std::uint64_t value = 1;
    if (k <= UIntModel::kTreeWidth) {
        const unsigned offset = (1u << (k - 1)) - 2;
        unsigned node = 1;
        for (unsigned i = low_bits; i-- > 0;) {
            const bool b = io.bit(m.tree[offset + node], (v >> i) & 1);
            node = node * 2 + b;
            value = value * 2 + b;
        }
        return value;
    }
    return (value << low_bits) | io.direct(v & ((std::uint64_t{1} << low_bits) - 1), low_bits);
}

void write_varint(std::vector<std::uint8_t>& out, std::uint64_t v) {
    while (v >= 0x80) {
        out.push_back(static_cast<std::uint8_t>(v | 0x80));
        v >>= 7;
    }
    out.push_back(static_cast<std::uint8_t>(v));
}

std::uint64_t read_varint(std::span<const std::uint8_t> bytes, std::size_t& position, const std::string& context) {
    std::uint64_t v = 0;
    for (unsigned shift = 0; shift < 64; shift += 7) {
        if (position >= bytes.size()) throw Error::input(context, "truncated stream header");
        const std::uint8_t byte = bytes[position++];
        v |= static_cast<std::uint64_t>(byte & 0x7F) << shift;
        if (!(byte & 0x80)) return v;
    }
    throw Error::input(context, "invalid stream header");
}

int sign_of(std::int64_t v) { return (v > 0) - (v < 0); }

// ---- Symbols: the structured (canonical) model ----------------------------------------------

constexpr int kParentBuckets = 7;  // parent component clamped to -3..3
constexpr int kNormBuckets = 12;   // |moves| already coded on earlier axes, clamped

struct SymbolModels {
    std::array<UIntModel, 3 * kParentBuckets * kNormBuckets> start_axis;
    std::array<BitModel, 3 * kParentBuckets> start_sign;
    std::array<BitModel, 2 * 4 * 4 * 4> correction_nonzero;
    std::array<UIntModel, 2 * 3 * 3 * 4> correction_axis;
    std::array<BitModel, 2 * 3 * 3 * 3> correction_sign;
    std::array<BitModel, 2 * 4 * 8 * 4 * 2> is_end_of_internode, is_fork;
};

// Replays the traversal queue of Pseudocode 1 on the coded internodes (identically in encoder and
// decoder) and provides the contexts of the next internode.
class ChainWalker {
public:
    bool start = true;                       // the next internode begins a branch: its vector is a full Δv
    Voxel chain_direction = Voxel::Zero();   // Δv of the previous internode of the branch
    Voxel parent_direction = Voxel::Zero();  // at a start: Δv of the internode that forked it off
    int since_start = 0;
    int since_fork = 0;                     // internodes since the branch's last fork (or its start)
    int order = 0;                          // branch order (0 trunk)
    unsigned recent_corrections = 0;        // were the last two corrections non-zero (2 bits)
    std::array<int, 3> last_sign{0, 0, 0};  // sign of the last non-zero correction per axis

    // `vector` is what the symbols code: Δv at a start, else the correction.
    void advance(const Voxel& vector, char terminator) {
        const Voxel move = start ? vector : Voxel(chain_direction + vector);
        if (!start) {
            for (int a = 0; a < 3; ++a) last_sign[a] = vector[a] != 0 ? sign_of(vector[a]) : last_sign[a];  // cmov
            recent_corrections = ((recent_corrections << 1) | (vector.isZero() ? 0u : 1u)) & 3u;
        }
        // Zero-length internodes at a branch start code further laterals of the same fork.
        const bool sibling_marker = start && move.isZero();
        if (terminator == kFork) queue_.push_back(sibling_marker ? Fork{parent_direction, order} : Fork{move, order + 1});
        if (terminator == kTip) {
            begin_branch();
        } else if (!(sibling_marker && terminator == kFork)) {
            start = false;
            chain_direction = move;
            ++since_start;
            since_fork = terminator == kFork ? 0 : since_fork + 1;
        }
    }

private:
    struct Fork {
        Voxel direction;
        int order;
    };
    void begin_branch() {
        start = true;
        since_start = 0;
        since_fork = 0;
        recent_corrections = 0;
        last_sign = {0, 0, 0};
        chain_direction = Voxel::Zero();
        parent_direction = Voxel::Zero();
        order = 0;
        if (next_ == queue_.size()) return;  // only at the end of a valid code
        parent_direction = queue_[next_].direction;
        order = queue_[next_].order;
        ++next_;
    }
    std::vector<Fork> queue_;  // a FIFO: queue_[next_..] wait for their lateral
    std::size_t next_ = 0;
};

// Codes the vector of one internode; `budget` caps the moves a decoder may produce.
template <class IO>
[[gnu::always_inline]] inline Voxel code_vector(IO& io, SymbolModels& m, const ChainWalker& w, Voxel v, std::uint64_t budget) {
    std::uint64_t used = 0;
    auto spend = [&](std::uint64_t magnitude) {
        used += magnitude;
        if (used > budget) io.fail("internode moves exceed the code length");
    };
    if (w.start) {
        for (int a = 0; a < 3; ++a) {
            const int parent = static_cast<int>(std::clamp<std::int64_t>(w.parent_direction[a], -3, 3)) + 3;
            const int norm = static_cast<int>(std::min<std::uint64_t>(used, kNormBuckets - 1));
            const std::uint64_t magnitude = code_uint(io, m.start_axis[(a * kParentBuckets + parent) * kNormBuckets + norm],
                                                      static_cast<std::uint64_t>(std::abs(v[a])));
            spend(magnitude);
            const bool negative = magnitude != 0 && io.bit(m.start_sign[a * kParentBuckets + parent], v[a] < 0);
            v[a] = negative ? -static_cast<std::int64_t>(magnitude) : static_cast<std::int64_t>(magnitude);
        }
        return v;
    }
    const int since = std::min(w.since_start, 3), order = std::min(w.order, 3);
    // A branch bends where it forks: a correction right after a fork is more likely and larger.
    const int after_fork = w.since_fork == 0 ? 1 : 0;
    if (!io.bit(m.correction_nonzero[((after_fork * 4 + w.recent_corrections) * 4 + since) * 4 + order], !v.isZero())) return Voxel::Zero();
    int nonzero_axes = 0;
    for (int a = 0; a < 3; ++a) {
        const bool implied = a == 2 && nonzero_axes == 0;  // a non-zero correction needs one axis
        const int direction = static_cast<int>(std::min<std::int64_t>(std::abs(w.chain_direction[a]), 3));
        const std::uint64_t magnitude = code_uint(io, m.correction_axis[((after_fork * 3 + a) * 3 + nonzero_axes) * 4 + direction],
                                                  static_cast<std::uint64_t>(std::abs(v[a])) - (IO::kEncoding && implied ? 1 : 0)) +
                                        (implied ? 1 : 0);
        spend(magnitude);
        bool negative = false;
        if (magnitude != 0) {
            ++nonzero_axes;
            negative = io.bit(m.correction_sign[((after_fork * 3 + a) * 3 + w.last_sign[a] + 1) * 3 + sign_of(w.chain_direction[a]) + 1],
                              v[a] < 0);
        }
        v[a] = negative ? -static_cast<std::int64_t>(magnitude) : static_cast<std::int64_t>(magnitude);
    }
    return v;
}

template <class IO>
[[gnu::always_inline]] inline char code_terminator(IO& io, SymbolModels& m, const ChainWalker& w, bool moved, char terminator) {
    // Forks come at fairly regular spacings along a branch: the distance to the last one matters.
    const int ctx =
            (((int(w.start) * 4 + std::min(w.since_start, 3)) * 8 + std::min(w.since_fork, 7)) * 4 + std::min(w.order, 3)) * 2 + int(moved);
    if (io.bit(m.is_end_of_internode[ctx], terminator == kEndOfInternode)) return kEndOfInternode;
    return io.bit(m.is_fork[ctx], terminator == kFork) ? kFork : kTip;
}

// Splits a code into internode vectors if every internode is canonical (ascending moves, never
// both directions on one axis, i.e. exactly what append_moves writes) and ends with a terminator.
bool canonical_internodes(const std::string& symbols, std::vector<std::pair<Voxel, char>>& out) {
    std::size_t begin = 0;
    std::string rewritten;
    for (std::size_t i = 0; i < symbols.size(); ++i) {
        if (!is_terminator(symbols[i])) continue;
        Voxel v = Voxel::Zero();
        for (std::size_t k = begin; k < i; ++k) v[(symbols[k] - '0') % 3] += symbols[k] < '3' ? 1 : -1;
        rewritten.clear();
        append_moves(v, rewritten);
        if (rewritten.size() != i - begin || symbols.compare(begin, i - begin, rewritten) != 0) return false;
        out.emplace_back(v, symbols[i]);
        begin = i + 1;
    }
    return begin == symbols.size();
}

// ---- Symbols: the fallback order-2 model for non-canonical codes ------------------------------

struct GenericModels {
    std::array<BitModel, 81 * 16> tree;  // context: previous two symbols; 4-bit symbol tree
};

template <class IO>
std::uint8_t code_generic_symbol(IO& io, GenericModels& m, unsigned context, std::uint8_t symbol) {
    unsigned node = 1;
    for (int i = 3; i >= 0; --i) node = node * 2 + io.bit(m.tree[context * 16 + node], (symbol >> i) & 1);
    const unsigned value = node - 16;
    if (value > 8) io.fail("corrupt symbol");
    return static_cast<std::uint8_t>(value);
}

// kInterpolative: the `ic` stream, kept when it is smaller (short or irregular codes).
enum SymbolMode : std::uint8_t { kGeneric = 0, kCanonical = 1, kInterpolativeSymbols = 2 };

// ---- Radii ------------------------------------------------------------------------------------

// The internode tree a code describes: parent internode (-1 for the first and for laterals whose
// fork is missing), tips below, whether it starts a branch, and its terminator.
struct Topology {
    std::vector<int> parent;
    std::vector<std::uint32_t> tips;
    std::vector<std::uint8_t> start;
    std::vector<char> terminator;
};

// The topology from the terminators of the internodes in code order. Without branches on the
// terminators (forks and tips are as unpredictable as the code): every index is written to the
// fork queue and kept by advancing its end only at a fork.
Topology topology_of(std::span<const char> terminators) {
    const std::size_t n = terminators.size();
    Topology t;
    t.parent.resize(n);
    t.start.resize(n);
    t.terminator.assign(terminators.begin(), terminators.end());
    std::vector<int> forks(n + 1);  // a FIFO queue: forks[next_fork..queued) wait for their lateral
    std::size_t queued = 0, next_fork = 0;
    bool start = true;
    for (std::size_t i = 0; i < n; ++i) {
        const char c = terminators[i];
        const int index = static_cast<int>(i);
        // A branch start takes the next queued fork (-1 when none is left: a corrupt code, or
        // the first internode).
        const bool takes_fork = start && index > 0;
        const bool available = next_fork < queued;
        const int lateral_parent = available ? forks[next_fork] : -1;
        t.parent[i] = takes_fork ? lateral_parent : index - 1;
        next_fork += std::size_t{takes_fork && available};
        t.start[i] = start;
        forks[queued] = index;
        queued += std::size_t{c == kFork};
        start = c == kTip;
    }
    t.tips.assign(n, 0);
    for (std::size_t i = n; i-- > 0;) {  // parents precede their children
        t.tips[i] += std::uint32_t{t.terminator[i] == kTip};
        const int parent = t.parent[i];
        if (parent >= 0) t.tips[static_cast<std::size_t>(parent)] += t.tips[i];
    }
    return t;
}

std::vector<char> terminators_of(const std::string& symbols) {
    std::vector<char> terminators;
    for (char c : symbols)
        if (is_terminator(c)) terminators.push_back(c);
    return terminators;
}

Topology parse_topology(const std::string& symbols) { return topology_of(terminators_of(symbols)); }

// kInterpolativeRadii: the `ic` radii stream, kept when it is smaller (very smooth radii, e.g.
// allometric radii of reconstructions, where interpolative coding codes runs of equal gaps in 0 bits).
enum RadiusPredictor : std::uint8_t { kParentRadius = 0, kPipeModel = 1, kInterpolativeRadii = 2 };

std::uint64_t isqrt(std::uint64_t x) {
    auto r = static_cast<std::uint64_t>(std::sqrt(static_cast<double>(x)));
    while (r > 0 && r * r > x) --r;  // exact floor whatever the libm rounding
    while ((r + 1) * (r + 1) <= x) ++r;
    return r;
}

// r_parent · sqrt(tips / tips_parent), rounded, in integers (deterministic on every platform).
std::int64_t predict_radius(const Topology& t, std::span<const int> radii, std::size_t i, RadiusPredictor predictor) {
    const int parent = t.parent[i];
    if (parent < 0) return 0;
    const std::int64_t reference = radii[parent];
    if (predictor == kParentRadius || reference <= 0 || t.tips[parent] == 0 || t.tips[i] >= t.tips[parent]) return reference;
    const auto square = static_cast<unsigned __int128>(reference) * static_cast<unsigned __int128>(reference) * 4u;
    const unsigned __int128 scaled = square * t.tips[i];
    // < 4 r^2 < 2^64; a 64-bit division when the product fits (always for real radii), as the
    // 128-bit one is a slow library call.
    const auto x =
            (scaled >> 64) == 0 ? static_cast<std::uint64_t>(scaled) / t.tips[parent] : static_cast<std::uint64_t>(scaled / t.tips[parent]);
    return static_cast<std::int64_t>((isqrt(x) + 1) / 2);
}

constexpr int kPredictedBuckets = 17;

struct RadiusModels {
    std::array<UIntModel, 2 * 3 * kPredictedBuckets * 3> residual;
    std::array<BitModel, 2 * kPredictedBuckets * 3> sign;
};

// 8 -> 0, 6 -> 1, 7 -> 2; and 0, |e| <= 2, larger -> 0, 1, 2: context indices computed without
// branches, as the decoded values they depend on are unpredictable.
int terminator_index(char c) { return (c - kFork + 1) % 3; }
int residual_bucket(std::int64_t e) { return int(e != 0) + int(std::abs(e) > 2); }

template <class IO>
void code_radii(IO& io, const Topology& t, std::span<int> radii, RadiusPredictor predictor, RadiusModels* models) {
    std::vector<std::int64_t> residuals(radii.size(), 0);
    for (std::size_t i = 0; i < radii.size(); ++i) {
        const std::int64_t predicted = predict_radius(t, radii, i, predictor);
        const int magnitude_bucket =
                static_cast<int>(std::min<unsigned>(bit_width64(static_cast<std::uint64_t>(std::abs(predicted))), kPredictedBuckets - 1));
        const std::int64_t parent_residual = t.parent[i] >= 0 ? residuals[t.parent[i]] : 0;
        const int ctx = ((int(t.start[i]) * 3 + terminator_index(t.terminator[i])) * kPredictedBuckets + magnitude_bucket) * 3 +
                        residual_bucket(parent_residual);
        const std::int64_t e = IO::kEncoding ? radii[i] - predicted : 0;
        const std::uint64_t magnitude = code_uint(io, models->residual[ctx], static_cast<std::uint64_t>(std::abs(e)));
        const int sign_ctx = (int(t.start[i]) * kPredictedBuckets + magnitude_bucket) * 3 + sign_of(parent_residual) + 1;
        const bool negative = magnitude != 0 && io.bit(models->sign[sign_ctx], e < 0);
        if (magnitude > (std::uint64_t{1} << 33)) io.fail("radius residual out of range");
        residuals[i] = negative ? -static_cast<std::int64_t>(magnitude) : static_cast<std::int64_t>(magnitude);
        const std::int64_t radius = predicted + residuals[i];
        if (radius < INT32_MIN || radius > INT32_MAX) io.fail("decoded radius out of range");
        radii[i] = static_cast<int>(radius);
    }
}

std::vector<std::uint8_t> encode_radii_with(const Topology& t, std::span<const int> radii, RadiusPredictor predictor,
                                            const RadiusModels& initial) {
    Encoding io;
    std::vector<int> copy(radii.begin(), radii.end());
    auto models = std::make_unique<RadiusModels>(initial);
    code_radii(io, t, copy, predictor, models.get());
    std::vector<std::uint8_t> out{predictor};
    const std::vector<std::uint8_t> payload = io.rc.finish();
    out.insert(out.end(), payload.begin(), payload.end());
    return out;
}

// Codes the internodes of a canonical code with `models` (encoder side; also trains priors).
void encode_canonical(Encoding& io, SymbolModels& models, const std::vector<std::pair<Voxel, char>>& internodes, std::size_t symbol_count) {
    ChainWalker walker;
    for (const auto& [vector, terminator] : internodes) {
        code_vector(io, models, walker, vector, symbol_count);
        code_terminator(io, models, walker, !vector.isZero(), terminator);
        walker.advance(vector, terminator);
    }
}

// Prior confidence: a trained model counts as this many observations, so each tree still moves
// it at rate ~1/(kPriorConfidence + 1.5) at first.
constexpr std::uint8_t kPriorConfidence = 16;

}  // namespace

struct BestPrior::State {
    SymbolModels symbols;
    RadiusModels radii;
};

namespace {

// The state is a plain array of BitModels (every model struct is arrays of them).
static_assert(sizeof(BitModel) == 4 && sizeof(BestPrior::State) % sizeof(BitModel) == 0);
static_assert(std::is_trivially_copyable_v<BestPrior::State>);
constexpr std::size_t kPriorModels = sizeof(BestPrior::State) / sizeof(BitModel);

BitModel* models_of(BestPrior::State& state) { return reinterpret_cast<BitModel*>(&state); }

std::unique_ptr<SymbolModels> symbol_models(const BestPrior* prior) {
    return prior ? std::make_unique<SymbolModels>(prior->state().symbols) : std::make_unique<SymbolModels>();
}

// The decoders' working models, one buffer per thread reset from `initial` (or the uniform
// models): a forest decodes hundreds of streams, and allocating and freeing ~110 KB for each
// made glibc trim and regrow the heap (page faults, malloc_consolidate) on the hot path.
template <class Models>
Models& scratch_models(const Models* initial) {
    static const Models uniform{};
    thread_local const std::unique_ptr<Models> buffer = std::make_unique<Models>();
    *buffer = initial ? *initial : uniform;
    return *buffer;
}

}  // namespace

BestPrior::BestPrior() : state_(std::make_unique<State>()) {}
BestPrior::~BestPrior() = default;
BestPrior::BestPrior(BestPrior&&) noexcept = default;
BestPrior& BestPrior::operator=(BestPrior&&) noexcept = default;

BestPrior BestPrior::train(const std::vector<const ChainCode*>& codes) {
    BestPrior prior;
    for (const ChainCode* code : codes) {
        std::vector<std::pair<Voxel, char>> internodes;
        if (!canonical_internodes(code->symbols, internodes)) continue;
        Encoding symbols_io;
        encode_canonical(symbols_io, prior.state_->symbols, internodes, code->symbols.size());
        const Topology topology = parse_topology(code->symbols);
        if (topology.parent.size() != code->radii.size() || code->radii.empty()) continue;
        Encoding radii_io;
        std::vector<int> copy = code->radii;
        code_radii(radii_io, topology, copy, kParentRadius, &prior.state_->radii);
    }
    BitModel* m = models_of(*prior.state_);
    for (std::size_t i = 0; i < kPriorModels; ++i) m[i].seen = std::min(m[i].seen, kPriorConfidence);
    const std::vector<std::uint8_t> bytes = prior.serialize();
    return deserialize(bytes, "trained prior");
}

// Layout: model count (u32 LE), then zlib of the high byte of every p0 followed by every `seen`.
std::vector<std::uint8_t> BestPrior::serialize() const {
    const BitModel* m = models_of(*state_);
    std::vector<std::uint8_t> raw(2 * kPriorModels);
    for (std::size_t i = 0; i < kPriorModels; ++i) {
        raw[i] = static_cast<std::uint8_t>(m[i].p0 >> 8);
        raw[kPriorModels + i] = m[i].seen;
    }
    uLongf size = compressBound(static_cast<uLong>(raw.size()));
    std::vector<std::uint8_t> out(4 + size);
    for (int b = 0; b < 4; ++b) out[static_cast<std::size_t>(b)] = static_cast<std::uint8_t>(kPriorModels >> (8 * b));
    if (compress2(out.data() + 4, &size, raw.data(), static_cast<uLong>(raw.size()), 9) != Z_OK)
        throw Error(ExitCode::Internal, "prior: zlib compression failed");
    out.resize(4 + size);
    return out;
}

BestPrior BestPrior::deserialize(std::span<const std::uint8_t> bytes, const std::string& context) {
    if (bytes.size() < 4) throw Error::input(context, "truncated model prior");
    std::uint32_t count = 0;
    for (int b = 0; b < 4; ++b) count |= static_cast<std::uint32_t>(bytes[static_cast<std::size_t>(b)]) << (8 * b);
    if (count != kPriorModels)
        throw Error::input(context,
                           "model prior of " + std::to_string(count) + " models (this build has " + std::to_string(kPriorModels) + ")");
    std::vector<std::uint8_t> raw(2 * kPriorModels);
    uLongf size = static_cast<uLongf>(raw.size());
    if (uncompress(raw.data(), &size, bytes.data() + 4, static_cast<uLong>(bytes.size() - 4)) != Z_OK || size != raw.size())
        throw Error::input(context, "corrupt model prior");
    BestPrior prior;
    BitModel* m = models_of(*prior.state_);
    for (std::size_t i = 0; i < kPriorModels; ++i) {
        // Centre of the quantization step, kept inside the range update() maintains.
        m[i].p0 = static_cast<std::uint16_t>(std::clamp((raw[i] << 8) + 128, 64, 65535 - 64));
        m[i].seen = std::min<std::uint8_t>(raw[kPriorModels + i], BitModel::kLimit);
    }
    return prior;
}

std::vector<std::uint8_t> best_encode_symbols(const std::string& symbols, const BestPrior* prior) {
    std::vector<std::uint8_t> out;
    write_varint(out, symbols.size());
    std::vector<std::pair<Voxel, char>> internodes;
    Encoding io;
    if (canonical_internodes(symbols, internodes)) {
        out.push_back(kCanonical);
        encode_canonical(io, *symbol_models(prior), internodes, symbols.size());
    } else {
        out.push_back(kGeneric);
        auto models = std::make_unique<GenericModels>();
        unsigned context = 8 * 9 + 8;
        for (char c : symbols) {
            const auto symbol = static_cast<std::uint8_t>(c - '0');
            code_generic_symbol(io, *models, context, symbol);
            context = (context % 9) * 9 + symbol;
        }
    }
    const std::vector<std::uint8_t> payload = io.rc.finish();
    out.insert(out.end(), payload.begin(), payload.end());
    std::vector<std::uint8_t> interpolative;
    write_varint(interpolative, symbols.size());
    interpolative.push_back(kInterpolativeSymbols);
    const std::vector<std::uint8_t> ic = ic_encode_symbols(symbols);
    interpolative.insert(interpolative.end(), ic.begin(), ic.end());
    return interpolative.size() < out.size() ? interpolative : out;
}

namespace {

// Slack a buffer needs behind its last move for write_moves.
constexpr std::size_t kMoveSlack = 8;

// `count` copies of `move` at `out`. Runs of up to 8 (nearly all) are one 8-byte store and a
// pointer increment, without a loop whose exit depends on the decoded count: the counts are as
// unpredictable as the code, so per-move loops mispredicted several times per internode.
char* write_run(char* out, char move, std::int64_t count) {
    if (count <= static_cast<std::int64_t>(kMoveSlack)) [[likely]] {
        std::memset(out, move, kMoveSlack);
        return out + count;
    }
    std::memset(out, move, static_cast<std::size_t>(count));
    return out + count;
}

// append_moves into a buffer with room for the moves plus kMoveSlack bytes: the decoder's hot
// loop, where append_moves's string growth showed as 6 % of the stream decoding profile.
char* write_moves(const Voxel& v, char* out) {
    for (int axis = 0; axis < 3; ++axis) out = write_run(out, static_cast<char>('0' + axis), std::max<std::int64_t>(v[axis], 0));
    for (int axis = 0; axis < 3; ++axis) out = write_run(out, static_cast<char>('3' + axis), std::max<std::int64_t>(-v[axis], 0));
    return out;
}

// The internodes of a canonical stream of `n` symbols: emit(vector, terminator) for each.
template <class Emit>
void decode_canonical(Decoding& io, SymbolModels& models, std::uint64_t n, Emit emit) {
    ChainWalker walker;
    std::uint64_t remaining = n;
    while (remaining > 0) {
        // The budget leaves room for the moves and the terminator among the n symbols.
        const Voxel vector = code_vector(io, models, walker, Voxel::Zero(), remaining - 1);
        const char terminator = code_terminator(io, models, walker, !vector.isZero(), kTip);
        remaining -= static_cast<std::uint64_t>(vector.cwiseAbs().sum()) + 1;
        emit(vector, terminator);
        walker.advance(vector, terminator);
    }
}

struct SymbolHeader {
    std::uint64_t count = 0;  // symbols of the code
    std::uint8_t mode = kCanonical;
    std::span<const std::uint8_t> payload;
};

SymbolHeader read_symbol_header(std::span<const std::uint8_t> bytes, const std::string& context) {
    std::size_t position = 0;
    SymbolHeader header;
    header.count = read_varint(bytes, position, context);
    if (header.count > kMaxCodeSymbols)
        throw Error::input(context, "code length " + std::to_string(header.count) + " exceeds the decoder limit");
    if (position >= bytes.size()) throw Error::input(context, "truncated stream header");
    header.mode = bytes[position++];
    if (header.mode != kInterpolativeSymbols && header.mode != kCanonical && header.mode != kGeneric)
        throw Error::input(context, "unknown symbol model " + std::to_string(header.mode));
    header.payload = bytes.subspan(position);
    return header;
}

// best_decode_symbols, also returning the terminators of the internodes (the radii decoder's
// topology) without a second scan of the symbol string.
std::string decode_symbols(std::span<const std::uint8_t> bytes, const std::string& context, const BestPrior* prior,
                           std::vector<char>& terminators) {
    const SymbolHeader header = read_symbol_header(bytes, context);
    const std::uint64_t n = header.count;
    const std::uint8_t mode = header.mode;
    const std::size_t position = static_cast<std::size_t>(header.payload.data() - bytes.data());
    if (mode == kInterpolativeSymbols) {
        std::string symbols = ic_decode_symbols(bytes.subspan(position), context);
        if (symbols.size() != n) throw Error::input(context, "symbol count disagrees with the stream header");
        terminators = terminators_of(symbols);
        return symbols;
    }
    Decoding io{RangeDecoder(bytes.subspan(position), context)};
    std::string symbols;
    symbols.reserve(n);
    if (mode == kCanonical) {
        terminators.reserve(n / 2);  // codes average about two symbols per internode
        symbols.resize(n + kMoveSlack);
        char* out = symbols.data();
        decode_canonical(io, scratch_models(prior ? &prior->state().symbols : nullptr), n, [&](const Voxel& vector, char terminator) {
            out = write_moves(vector, out);
            *out++ = terminator;
            terminators.push_back(terminator);
        });
        symbols.resize(n);
    } else {
        auto models = std::make_unique<GenericModels>();
        unsigned ctx = 8 * 9 + 8;
        while (symbols.size() < n) {
            const std::uint8_t symbol = code_generic_symbol(io, *models, ctx, 0);
            symbols += static_cast<char>('0' + symbol);
            ctx = (ctx % 9) * 9 + symbol;
        }
        terminators = terminators_of(symbols);
    }
    if (!io.rc.at_end()) throw Error::input(context, "trailing bytes after the symbol stream");
    return symbols;
}

}  // namespace

std::string best_decode_symbols(std::span<const std::uint8_t> bytes, const std::string& context, const BestPrior* prior) {
    std::vector<char> terminators;
    return decode_symbols(bytes, context, prior, terminators);
}

std::vector<std::uint8_t> best_encode_radii(const std::string& symbols, std::span<const int> radii, const BestPrior* prior) {
    const Topology topology = parse_topology(symbols);
    if (topology.parent.size() != radii.size())
        throw Error(ExitCode::Internal, "best radii: radius count differs from the internode count");
    if (radii.empty()) return {};
    const auto uniform = std::make_unique<RadiusModels>();
    const RadiusModels& initial = prior ? prior->state().radii : *uniform;
    std::vector<std::uint8_t> best = encode_radii_with(topology, radii, kParentRadius, initial);
    std::vector<std::uint8_t> pipe = encode_radii_with(topology, radii, kPipeModel, initial);
    if (pipe.size() < best.size()) best = std::move(pipe);
    std::vector<std::uint8_t> interpolative{kInterpolativeRadii};
    const std::vector<std::uint8_t> ic = ic_encode_radii(symbols, radii);
    interpolative.insert(interpolative.end(), ic.begin(), ic.end());
    return interpolative.size() < best.size() ? interpolative : best;
}

namespace {

// `symbols()` gives the code's symbol string, which only the `ic` fallback stream needs.
template <class Symbols>
std::vector<int> decode_radii(std::span<const std::uint8_t> bytes, Symbols symbols, const Topology& topology, const std::string& context,
                              const BestPrior* prior) {
    std::vector<int> radii(topology.parent.size(), 0);
    if (radii.empty()) {
        if (!bytes.empty()) throw Error::input(context, "radii stream for a code without internodes");
        return radii;
    }
    if (bytes.empty()) throw Error::input(context, "empty radii stream");
    const std::uint8_t predictor = bytes[0];
    if (predictor == kInterpolativeRadii) return ic_decode_radii(bytes.subspan(1), symbols(), context);
    if (predictor != kParentRadius && predictor != kPipeModel)
        throw Error::input(context, "unknown radius predictor " + std::to_string(predictor));
    Decoding io{RangeDecoder(bytes.subspan(1), context)};
    RadiusModels& models = scratch_models(prior ? &prior->state().radii : nullptr);
    code_radii(io, topology, radii, static_cast<RadiusPredictor>(predictor), &models);
    if (!io.rc.at_end()) throw Error::input(context, "trailing bytes after the radii stream");
    return radii;
}

}  // namespace

std::vector<int> best_decode_radii(std::span<const std::uint8_t> bytes, const std::string& symbols, const std::string& context,
                                   const BestPrior* prior) {
    return decode_radii(
            bytes, [&]() -> const std::string& { return symbols; }, parse_topology(symbols), context, prior);
}

ChainCode best_decode_code(std::span<const std::uint8_t> symbol_bytes, std::span<const std::uint8_t> radii_bytes,
                           const std::string& symbols_context, const std::string& radii_context, const BestPrior* prior) {
    ChainCode code;
    std::vector<char> terminators;
    code.symbols = decode_symbols(symbol_bytes, symbols_context, prior, terminators);
    code.radii = decode_radii(
            radii_bytes, [&]() -> const std::string& { return code.symbols; }, topology_of(terminators), radii_context, prior);
    return code;
}

InternodeVectors best_decode_internodes(std::span<const std::uint8_t> symbol_bytes, std::span<const std::uint8_t> radii_bytes,
                                        const std::string& symbols_context, const std::string& radii_context, const BestPrior* prior) {
    const SymbolHeader header = read_symbol_header(symbol_bytes, symbols_context);
    if (header.mode != kCanonical)
        return internode_vectors(best_decode_code(symbol_bytes, radii_bytes, symbols_context, radii_context, prior), symbols_context);
    InternodeVectors code;
    code.vectors.reserve(header.count / 2);  // codes average about two symbols per internode
    code.terminators.reserve(header.count / 2);
    Decoding io{RangeDecoder(header.payload, symbols_context)};
    decode_canonical(io, scratch_models(prior ? &prior->state().symbols : nullptr), header.count,
                     [&](const Voxel& vector, char terminator) {
                         code.vectors.push_back(vector);
                         code.terminators.push_back(terminator);
                     });
    if (!io.rc.at_end()) throw Error::input(symbols_context, "trailing bytes after the symbol stream");
    std::string symbols;
    code.radii = decode_radii(
            radii_bytes, [&]() -> const std::string& { return symbols = symbol_text(code); }, topology_of(code.terminators), radii_context,
            prior);
    return code;
}

}  // namespace treelobes::encode
