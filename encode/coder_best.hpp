// The `best` coder: adaptive binary arithmetic coding with contexts taken from the structure of
// the chain code (docs/compression.md gives the measurements behind every choice).
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
#pragma once

#include "encode/coder.hpp"

namespace treelobes::encode {

std::vector<std::uint8_t> best_encode_symbols(const std::string& symbols);
std::string best_decode_symbols(std::span<const std::uint8_t> bytes, const std::string& context);

std::vector<std::uint8_t> best_encode_radii(const std::string& symbols, std::span<const int> radii);
std::vector<int> best_decode_radii(std::span<const std::uint8_t> bytes, const std::string& symbols,
                                   const std::string& context);

}  // namespace treelobes::encode
