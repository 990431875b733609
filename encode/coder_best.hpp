// The `best` coder: adaptive binary arithmetic coding with contexts taken from the structure of
// the chain code (docs/dbf6.md gives the measurements).
//
// Symbols. A DBF6 code is a sequence of internodes, each a set of moves written in ascending
// order (so it is just a vector) plus a terminator 6/7/8. The coder replays the traversal queue
// of Pseudocode 1 while it codes, so it knows for every internode whether it starts a branch
// (its vector is a full Δv, coded per axis given the parent's direction at the fork and the
// axes already coded) or continues one (its vector is a correction, mostly zero, whose sign on an
// axis usually flips the previous correction on that axis: voxel rounding alternates), how many
// internodes the branch has so far and the branch order — which predict the terminator.
// A code whose internodes are not in that canonical form is coded symbol by symbol with an
// order-2 context model instead, so any string of 0..8 round-trips.
//
// Radii. Coded after the symbols, so the whole topology is known: every radius is predicted from
// the radius of the internode it grows from, either unchanged or scaled by the pipe model
// sqrt(tips below it / tips below the parent) (integer arithmetic, identical on every platform);
// the encoder keeps whichever predictor gives the smaller stream. Residuals are coded with
// contexts of branch start, terminator, predicted magnitude and the parent's residual.
//
// Each stream falls back to the `ic` coding of the same data (one mode byte says which) when
// that is smaller: very smooth radii (allometric radii of reconstructions) have long runs of
// equal gaps that interpolative coding codes in 0 bits, below the arithmetic coder's cost.
#pragma once

#include "encode/coder.hpp"

#include <memory>

namespace treelobes::encode {

// Initial state of the adaptive models. A lone tree starts from the uniform state; the trees of
// a .forest file start from a prior trained on all of them and stored once in the file
// (forest_file.hpp), so that small trees do not each pay again for learning the statistics.
class BestPrior {
public:
    BestPrior();  // the uniform state
    ~BestPrior();
    BestPrior(BestPrior&&) noexcept;
    BestPrior& operator=(BestPrior&&) noexcept;

    // Adapts the models to `codes` in turn, as the encoder codes them, then caps their confidence
    // so that every tree still adapts. Returns the prior as its stored bytes decode it, which is
    // what encoder and decoder must both start from.
    static BestPrior train(const std::vector<const ChainCode*>& codes);
    std::vector<std::uint8_t> serialize() const;
    // Throws Error(InvalidInput) naming `context` for bytes that are not a prior.
    static BestPrior deserialize(std::span<const std::uint8_t> bytes, const std::string& context);

    struct State;
    const State& state() const { return *state_; }

private:
    std::unique_ptr<State> state_;
};

std::vector<std::uint8_t> best_encode_symbols(const std::string& symbols, const BestPrior* prior = nullptr);
std::string best_decode_symbols(std::span<const std::uint8_t> bytes, const std::string& context, const BestPrior* prior = nullptr);

std::vector<std::uint8_t> best_encode_radii(const std::string& symbols, std::span<const int> radii, const BestPrior* prior = nullptr);
std::vector<int> best_decode_radii(std::span<const std::uint8_t> bytes, const std::string& symbols, const std::string& context,
                                   const BestPrior* prior = nullptr);

// Both streams at once, as best_decode_symbols then best_decode_radii but faster: the radii
// decoder takes the topology from the symbol decoder instead of re-scanning the symbol string.
ChainCode best_decode_code(std::span<const std::uint8_t> symbol_bytes, std::span<const std::uint8_t> radii_bytes,
                           const std::string& symbols_context, const std::string& radii_context, const BestPrior* prior = nullptr);

// best_decode_code in internode form (chain_code.hpp), for decoders that build skeletons: a
// canonical symbol stream then never becomes text. Same checks and errors.
InternodeVectors best_decode_internodes(std::span<const std::uint8_t> symbol_bytes, std::span<const std::uint8_t> radii_bytes,
                                        const std::string& symbols_context, const std::string& radii_context,
                                        const BestPrior* prior = nullptr);

}  // namespace treelobes::encode
