#include "encode/coder.hpp"

#include "core/error.hpp"
#include "encode/coder_best.hpp"
#include "encode/coder_ic.hpp"

#include <algorithm>

namespace treelobes::encode {

const char* coder_name(Coder coder) { return coder == Coder::Interpolative ? "ic" : "best"; }

Coder parse_coder(const std::string& name) {
    if (name == "ic") return Coder::Interpolative;
    if (name == "best") return Coder::Best;
    throw Error::usage("unknown coder '" + name + "' (--coder takes ic or best)");
}

void check_code_for_coding(const ChainCode& code, const std::string& context) {
    std::size_t internodes = 0;
    for (std::size_t i = 0; i < code.symbols.size(); ++i) {
        const char c = code.symbols[i];
        if (c < '0' || c > '8')
            throw Error::input(context, std::string("chain code symbol '") + c + "' at character " + std::to_string(i + 1) + " is not 0-8");
        if (c >= '6') ++internodes;
    }
    if (code.symbols.size() > kMaxCodeSymbols) throw Error::input(context, "chain code too long to store");
    if (internodes != code.radii.size())
        throw Error::input(context, "the radius list has " + std::to_string(code.radii.size()) + " values for " +
                                            std::to_string(internodes) + " internodes");
}

CodedStreams encode_streams(const ChainCode& code, Coder coder, const std::string& context, const BestPrior* prior) {
    check_code_for_coding(code, context);
    if (coder == Coder::Interpolative) return {ic_encode_symbols(code.symbols), ic_encode_radii(code.symbols, code.radii)};
    return {best_encode_symbols(code.symbols, prior), best_encode_radii(code.symbols, code.radii, prior)};
}

ChainCode decode_streams(std::span<const std::uint8_t> symbols, std::span<const std::uint8_t> radii, Coder coder, CodeKind kind,
                         const std::string& context, const BestPrior* prior) {
    ChainCode code;
    code.kind = kind;
    if (coder == Coder::Interpolative) {
        code.symbols = ic_decode_symbols(symbols, context + " (symbols)");
        code.radii = ic_decode_radii(radii, code.symbols, context + " (radii)");
    } else if (coder == Coder::Best) {
        code = best_decode_code(symbols, radii, context + " (symbols)", context + " (radii)", prior);
        code.kind = kind;
    } else {
        throw Error::input(context, "unknown coder " + std::to_string(static_cast<int>(coder)));
    }
    return code;
}

InternodeVectors decode_stream_internodes(std::span<const std::uint8_t> symbols, std::span<const std::uint8_t> radii, Coder coder,
                                          CodeKind kind, const std::string& context, const BestPrior* prior) {
    InternodeVectors code = coder == Coder::Best
                                    ? best_decode_internodes(symbols, radii, context + " (symbols)", context + " (radii)", prior)
                                    : internode_vectors(decode_streams(symbols, radii, coder, kind, context, prior), context);
    code.kind = kind;
    return code;
}

}  // namespace treelobes::encode
