// The two entropy coders of chain codes and radii (Strnad et al. 2020, §3.3 and the project's own), behind
// one interface used by the .dbf6 and .forest containers. Each coder turns a ChainCode into two
// byte streams — the symbols and the radii — so their sizes can be reported separately; the
// radii stream is decoded after the symbols because both coders use the code's structure.
#pragma once

#include "encode/chain_code.hpp"

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace treelobes::encode {

enum class Coder : std::uint8_t {
    Interpolative = 1,  // `ic`: BWT, MTF, cumulative sum, binary interpolative coding (§3.3)
    Best = 2,           // `best`: context-modelled binary arithmetic coding (docs/dbf6.md)
};
const char* coder_name(Coder coder);
// "ic" or "best"; throws Error(Usage) otherwise.
Coder parse_coder(const std::string& name);

struct CodedStreams {
    std::vector<std::uint8_t> symbols;
    std::vector<std::uint8_t> radii;
};

// Decoders refuse codes longer than this: a corrupt count must not allocate gigabytes, and the
// interpolative coder stores a run of equal values in no bits at all, so a few hundred bytes can
// claim any count (fuzz/forest_fuzz.cpp found one decoding for 19 s under ASan at the old limit of
// 2^28). The largest real trees have ~10^5 internodes and ~10^6 symbols: 2^24 leaves 16x.
inline constexpr std::size_t kMaxCodeSymbols = std::size_t{1} << 24;

// Throws Error(InvalidInput) naming `context` when a symbol is not 0..8 or the number of radii
// differs from the number of internodes (6, 7 and 8).
void check_code_for_coding(const ChainCode& code, const std::string& context);

class BestPrior;  // coder_best.hpp: initial model state shared by the trees of a forest

// `prior` (Best only; nullptr = uniform start) must be the same for encoding and decoding.
CodedStreams encode_streams(const ChainCode& code, Coder coder, const std::string& context = "chain code",
                            const BestPrior* prior = nullptr);
// Inverse of encode_streams; `kind` is carried by the container. Throws Error(InvalidInput)
// naming `context` for any corrupt or truncated stream.
ChainCode decode_streams(std::span<const std::uint8_t> symbols, std::span<const std::uint8_t> radii, Coder coder, CodeKind kind,
                         const std::string& context = "chain code", const BestPrior* prior = nullptr);

// decode_streams in internode form (chain_code.hpp), for decoders that build skeletons.
InternodeVectors decode_stream_internodes(std::span<const std::uint8_t> symbols, std::span<const std::uint8_t> radii, Coder coder,
                                          CodeKind kind, const std::string& context = "chain code", const BestPrior* prior = nullptr);

}  // namespace treelobes::encode
