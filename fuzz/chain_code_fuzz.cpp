// Chain codes as `treelobes decode-code` and `lod` take them: the first line is the symbol
// string, the rest the radius list. The code is decoded as DBF6 and as F6 and LOD-reduced.
#include "encode/chain_code.hpp"
#include "encode/lod.hpp"
#include "encode/tree_code.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    using namespace treelobes::encode;
    const std::string_view text = treelobes::fuzz::as_text(data, size);
    const std::size_t newline = text.find('\n');
    if (newline == std::string_view::npos) return 0;
    treelobes::fuzz::expect_only_input_errors([&] {
        ChainCode code;
        code.symbols = std::string(text.substr(0, newline));
        code.radii = parse_radius_list(std::string(text.substr(newline + 1)), "--radii");
        CodeGeometry geometry;
        geometry.voxel_size = 0.01;
        for (const CodeKind kind : {CodeKind::DBF6, CodeKind::F6}) {
            code.kind = kind;
            treelobes::fuzz::expect_only_input_errors([&] { decode_tree(code, geometry, "--code"); });
        }
        treelobes::fuzz::expect_only_input_errors([&] { lod_chain(code, lod_thresholds(branch_thicknesses(code), 3), "--code"); });
    });
    return 0;
}
