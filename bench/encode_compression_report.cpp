// Strnad et al. 2020, §4, Experiments 2 and 3 (Tables 5 and 6) for our synthetic trees, plus the comparison of
// the `best` coder with general-purpose compressors (the target: `best` at least 15 % smaller than the best of them):
//   encode_compression_report [--trees N] [--runs K] [SKELETON.ply ...]
// Table 5: for the 12 species trees of bench/compression_subjects.hpp (and any skeleton given),
// at r = 5: raw (16 bytes/internode), raw gzip -9, cc bin, cc gzip -9, cc ic, cc best and cc under
// xz -9e, zstd --ultra -22, brotli -q 11, bzip2 -9, with decode times. Table 6: a forest of N
// trees (default 400) with 1/3/5 LODs x r = 3/5/10: .forest size and full decode time (LOD 0 of
// every tree to placed skeletons, one thread). Prints Markdown; exits 1 if a round trip fails.
//
// "cc" bytes given to the general-purpose compressors: the chain code as one byte per symbol,
// then the radii; each compressor gets both a binary form (radii as LEB128 varints) and the text
// form of `treelobes encode --print-code` (radii in decimal), and keeps the smaller result.
#include "bench/compression_subjects.hpp"
#include "core/error.hpp"
#include "core/skeleton_io.hpp"
#include "encode/coder.hpp"
#include "encode/forest_file.hpp"
#include "encode/tree_file.hpp"

#include <brotli/encode.h>
#include <bzlib.h>
#include <lzma.h>
#include <zlib.h>
#include <zstd.h>

#include <algorithm>
#include <ctime>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

using namespace treelobes;
using namespace treelobes::encode;

namespace {

using Bytes = std::vector<std::uint8_t>;

// CPU time of this thread: on a shared machine it is far steadier than wall time (the decoders
// are single-threaded, so for an idle machine the two agree).
double thread_cpu_ms() {
    timespec t{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
    return static_cast<double>(t.tv_sec) * 1e3 + static_cast<double>(t.tv_nsec) * 1e-6;
}

// ---- General-purpose compressors at their strongest settings ---------------------------------

std::size_t gzip9(const Bytes& in) {
    z_stream s{};
    // windowBits 31 = gzip wrapper, memLevel 9: what `gzip -9` writes (modulo the file name).
    if (deflateInit2(&s, 9, Z_DEFLATED, 31, 9, Z_DEFAULT_STRATEGY) != Z_OK) throw Error(ExitCode::Internal, "zlib init");
    Bytes out(deflateBound(&s, in.size()) + 64);
    s.next_in = const_cast<Bytef*>(in.data());
    s.avail_in = static_cast<uInt>(in.size());
    s.next_out = out.data();
    s.avail_out = static_cast<uInt>(out.size());
    const int rc = deflate(&s, Z_FINISH);
    const std::size_t size = s.total_out;
    deflateEnd(&s);
    if (rc != Z_STREAM_END) throw Error(ExitCode::Internal, "zlib deflate");
    return size;
}

std::size_t bzip2_9(const Bytes& in) {
    unsigned int size = static_cast<unsigned int>(in.size() + in.size() / 100 + 600);
    Bytes out(size);
    if (BZ2_bzBuffToBuffCompress(reinterpret_cast<char*>(out.data()), &size, const_cast<char*>(reinterpret_cast<const char*>(in.data())),
                                 static_cast<unsigned int>(in.size()), 9, 0, 0) != BZ_OK)
        throw Error(ExitCode::Internal, "bzip2");
    return size;
}

std::size_t xz9e(const Bytes& in) {
    Bytes out(lzma_stream_buffer_bound(in.size()));
    std::size_t position = 0;
    if (lzma_easy_buffer_encode(9 | LZMA_PRESET_EXTREME, LZMA_CHECK_CRC64, nullptr, in.data(), in.size(), out.data(), &position,
                                out.size()) != LZMA_OK)
        throw Error(ExitCode::Internal, "xz");
    return position;
}

std::size_t zstd22(const Bytes& in) {
    Bytes out(ZSTD_compressBound(in.size()));
    const std::size_t size = ZSTD_compress(out.data(), out.size(), in.data(), in.size(), 22);
    if (ZSTD_isError(size)) throw Error(ExitCode::Internal, "zstd");
    return size;
}

std::size_t brotli11(const Bytes& in) {
    std::size_t size = BrotliEncoderMaxCompressedSize(in.size()) + 64;
    Bytes out(size);
    if (!BrotliEncoderCompress(11, 24, BROTLI_MODE_GENERIC, in.size(), in.data(), &size, out.data()))
        throw Error(ExitCode::Internal, "brotli");
    return size;
}

struct GeneralSizes {
    std::size_t gzip = 0, bzip2 = 0, xz = 0, zstd = 0, brotli = 0;
    std::size_t smallest() const { return std::min({gzip, bzip2, xz, zstd, brotli}); }
};

GeneralSizes compress_all(const std::vector<Bytes>& forms) {
    GeneralSizes best{SIZE_MAX, SIZE_MAX, SIZE_MAX, SIZE_MAX, SIZE_MAX};
    for (const Bytes& b : forms) {
        best.gzip = std::min(best.gzip, gzip9(b));
        best.bzip2 = std::min(best.bzip2, bzip2_9(b));
        best.xz = std::min(best.xz, xz9e(b));
        best.zstd = std::min(best.zstd, zstd22(b));
        best.brotli = std::min(best.brotli, brotli11(b));
    }
    return best;
}

// ---- Representations of a tree ----------------------------------------------------------------

void append_varint(Bytes& out, std::uint64_t v) {
    while (v >= 0x80) {
        out.push_back(static_cast<std::uint8_t>(v | 0x80));
        v >>= 7;
    }
    out.push_back(static_cast<std::uint8_t>(v));
}

Bytes cc_binary(const ChainCode& code) {
    Bytes out(code.symbols.begin(), code.symbols.end());
    out.push_back('\n');
    for (int r : code.radii) append_varint(out, static_cast<std::uint64_t>(r));
    return out;
}

Bytes cc_text(const ChainCode& code) {
    std::string text = code.symbols + "\n";
    for (std::size_t i = 0; i < code.radii.size(); ++i) {
        if (i) text += ',';
        text += std::to_string(code.radii[i]);
    }
    text += "\n";
    return {text.begin(), text.end()};
}

// The paper's "cc bin": 4 bits per symbol and the fewest bits that hold every radius.
std::size_t cc_bin_size(const ChainCode& code) {
    const int largest = code.radii.empty() ? 0 : *std::max_element(code.radii.begin(), code.radii.end());
    unsigned bits = 1;
    while ((1ull << bits) <= static_cast<unsigned long long>(largest)) ++bits;
    return (4 * code.symbols.size() + bits * code.radii.size() + 7) / 8;
}

// The paper's raw geometry: 16 bytes per internode. As bytes for "raw gzip": per internode in
// pre-order, its end vertex (float32 x, y, z, tree frame) and a 32-bit word holding the parent's
// index (20 bits) and the radius in millimetres (12 bits, saturated).
Bytes raw_geometry(const TreeGraph& tree) {
    Bytes out;
    const std::vector<int> order = tree.preorder();
    std::vector<std::uint32_t> rank(tree.size());
    for (std::size_t i = 0; i < order.size(); ++i) rank[static_cast<std::size_t>(order[i])] = static_cast<std::uint32_t>(i);
    for (int node : order) {
        const TreeNode& n = tree.nodes[static_cast<std::size_t>(node)];
        if (n.parent < 0) continue;
        for (int a = 0; a < 3; ++a) {
            std::uint32_t bits;
            std::memcpy(&bits, &n.position[a], 4);
            for (int b = 0; b < 4; ++b) out.push_back(static_cast<std::uint8_t>(bits >> (8 * b)));
        }
        const auto radius_mm = static_cast<std::uint32_t>(std::min(4095.0f, std::round(n.radius * 1000.0f)));
        const std::uint32_t word = (rank[static_cast<std::size_t>(n.parent)] & 0xFFFFFu) << 12 | radius_mm;
        for (int b = 0; b < 4; ++b) out.push_back(static_cast<std::uint8_t>(word >> (8 * b)));
    }
    return out;
}

// ---- Table 5 ----------------------------------------------------------------------------------

struct Row5 {
    std::string name;
    std::size_t internodes = 0, symbols = 0, raw = 0, raw_gzip = 0, cc_bin = 0, ic = 0, best = 0;
    StreamSizes ic_streams, best_streams;
    GeneralSizes general;
    double ic_ms = 0.0, best_ms = 0.0;
};

// Fastest of `runs` decodes of the file bytes into a skeleton (the machine is shared).
double decode_ms(const Bytes& file, const StoredTree& original, int runs, bool& ok) {
    double fastest = 1e300;
    for (int run = 0; run < runs; ++run) {
        const double start = thread_cpu_ms();
        const StoredTree decoded = read_tree_file_bytes(file, 0, "bench");
        const TreeGraph tree = decode_stored_tree(decoded, 0, "bench");
        fastest = std::min(fastest, thread_cpu_ms() - start);
        ok = ok && decoded.lods[0].symbols == original.lods[0].symbols && decoded.lods[0].radii == original.lods[0].radii &&
             tree.size() > 1;
    }
    return fastest;
}

Row5 measure_tree(const std::string& name, const TreeGraph& tree, int runs, bool& ok) {
    TreeFileOptions options;
    options.encode.resolution = 5.0;
    StoredTree stored = store_tree(tree, options, name);
    const ChainCode& code = stored.lods[0];
    Row5 row;
    row.name = name;
    row.internodes = code.radii.size();
    row.symbols = code.symbols.size();
    row.raw = 16 * row.internodes;
    row.raw_gzip = gzip9(raw_geometry(tree));
    row.cc_bin = cc_bin_size(code);
    row.general = compress_all({cc_binary(code), cc_text(code)});
    std::vector<StreamSizes> sizes;
    stored.coder = Coder::Interpolative;
    const Bytes ic = write_tree_file_bytes(stored, &sizes);
    row.ic_streams = sizes[0];
    stored.coder = Coder::Best;
    const Bytes best = write_tree_file_bytes(stored, &sizes);
    row.best_streams = sizes[0];
    row.ic = ic.size();
    row.best = best.size();
    row.ic_ms = decode_ms(ic, stored, runs, ok);
    row.best_ms = decode_ms(best, stored, runs, ok);
    return row;
}

void print_table5(const std::vector<Row5>& rows) {
    std::printf(
            "\n## Table 5: sizes in bytes at r = 5 (full detail)\n\n"
            "cc ic / cc best are whole .dbf6 files (header and CRC included); the factor in parentheses is raw / size.\n"
            "`best vs min` = cc best relative to the smallest general-purpose result.\n\n"
            "| tree | internodes | raw | raw gzip -9 | cc bin | cc gzip -9 | cc bzip2 -9 | cc xz -9e | cc zstd -22 | "
            "cc brotli -q 11 | cc ic | cc best | ic vs gzip | best vs min | ic decode ms | best decode ms |\n"
            "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    for (const Row5& r : rows) {
        const double raw = static_cast<double>(r.raw);
        std::printf(
                "| %s | %zu | %zu | %zu | %zu | %zu | %zu | %zu | %zu | %zu | %zu (%.1f) | %zu (%.1f) | %+.1f %% | %+.1f %% | "
                "%.2f | %.2f |\n",
                r.name.c_str(), r.internodes, r.raw, r.raw_gzip, r.cc_bin, r.general.gzip, r.general.bzip2, r.general.xz, r.general.zstd,
                r.general.brotli, r.ic, raw / r.ic, r.best, raw / r.best, 100.0 * (static_cast<double>(r.ic) / r.general.gzip - 1.0),
                100.0 * (static_cast<double>(r.best) / r.general.smallest() - 1.0), r.ic_ms, r.best_ms);
    }
    std::printf(
            "\n### Where the bytes go: symbol and radii streams (bytes), DBF6 symbols per internode\n\n"
            "| tree | symbols / internode | ic symbols | best symbols | best vs ic | ic radii | best radii | best vs ic |\n"
            "|---|---|---|---|---|---|---|---|\n");
    for (const Row5& r : rows)
        std::printf("| %s | %.2f | %zu | %zu | %+.1f %% | %zu | %zu | %+.1f %% |\n", r.name.c_str(),
                    static_cast<double>(r.symbols) / r.internodes, r.ic_streams.symbols, r.best_streams.symbols,
                    100.0 * (static_cast<double>(r.best_streams.symbols) / r.ic_streams.symbols - 1.0), r.ic_streams.radii,
                    r.best_streams.radii, 100.0 * (static_cast<double>(r.best_streams.radii) / r.ic_streams.radii - 1.0));
}

// ---- Table 6 ----------------------------------------------------------------------------------

struct Cell6 {
    std::size_t bytes = 0;
    double decode_ms = 0.0;
};

// Decodes LOD 0 of every tree to a placed skeleton, on this thread.
double decode_forest_ms(const Bytes& file, int runs, std::size_t& nodes) {
    double fastest = 1e300;
    for (int run = 0; run < runs; ++run) {
        const double start = thread_cpu_ms();
        ForestReader reader(file, "forest");
        nodes = 0;
        for (std::size_t i = 0; i < reader.size(); ++i) nodes += reader.decode(i, 0).size();
        fastest = std::min(fastest, thread_cpu_ms() - start);
    }
    return fastest;
}

void table6(const std::vector<ForestTree>& forest, int runs) {
    std::size_t internodes = 0;
    std::vector<ChainCode> codes;
    TreeFileOptions probe;
    for (const ForestTree& t : forest) {
        const StoredTree s = store_tree(t.skeleton, probe, t.name);
        internodes += s.lods[0].radii.size();
        codes.push_back(s.lods[0]);
    }
    // General-purpose compressors on the whole forest's cc bytes at r = 5 (one stream, so they
    // can exploit similarities between trees).
    Bytes binary, text;
    for (const ChainCode& c : codes) {
        const Bytes b = cc_binary(c), t = cc_text(c);
        binary.insert(binary.end(), b.begin(), b.end());
        text.insert(text.end(), t.begin(), t.end());
    }
    const GeneralSizes general = compress_all({binary, text});
    // The same compressors tree by tree, summed: what a file with random access to each tree
    // would get from them (each tree compressed on its own, like the trees of a .forest file).
    GeneralSizes per_tree{};
    for (const ChainCode& c : codes) {
        const GeneralSizes g = compress_all({cc_binary(c), cc_text(c)});
        per_tree.gzip += g.gzip;
        per_tree.bzip2 += g.bzip2;
        per_tree.xz += g.xz;
        per_tree.zstd += g.zstd;
        per_tree.brotli += g.brotli;
    }
    std::printf("\n## Table 6: forest of %zu trees, %zu internodes at r = 5 (raw %zu bytes)\n\n", forest.size(), internodes,
                16 * internodes);
    std::printf(
            "General-purpose compressors on the forest's code+radii bytes at r = 5, full detail: gzip -9 %zu, bzip2 -9 %zu, "
            "xz -9e %zu, zstd -22 %zu, brotli -q 11 %zu (smallest %zu).\n\n",
            general.gzip, general.bzip2, general.xz, general.zstd, general.brotli, general.smallest());
    std::printf(
            "The same compressors on each tree separately (random access), summed: gzip -9 %zu, bzip2 -9 %zu, "
            "xz -9e %zu, zstd -22 %zu, brotli -q 11 %zu (smallest %zu).\n\n",
            per_tree.gzip, per_tree.bzip2, per_tree.xz, per_tree.zstd, per_tree.brotli, per_tree.smallest());
    for (Coder coder : {Coder::Interpolative, Coder::Best}) {
        char note[400] = "";
        std::printf(
                "### coder %s: .forest size (full decode of LOD 0 to placed skeletons, one thread)\n\n"
                "| LODs | r = 3 | r = 5 | r = 10 |\n|---|---|---|---|\n",
                coder_name(coder));
        for (int lods : {1, 3, 5}) {
            std::printf("| %d |", lods);
            for (double r : {3.0, 5.0, 10.0}) {
                TreeFileOptions options;
                options.encode.resolution = r;
                options.lods = lods;
                options.coder = coder;
                const Bytes file = write_forest_bytes(forest, options);
                std::size_t nodes = 0;
                const double ms = decode_forest_ms(file, runs, nodes);
                std::printf(" %.3f MB (%.0f ms) |", static_cast<double>(file.size()) / 1e6, ms);
                if (lods == 1 && r == 5.0)
                    std::snprintf(note, sizeof note,
                                  "%s r=5 1 LOD: %zu bytes, %+.1f %% vs smallest general on the whole forest, "
                                  "%+.1f %% vs smallest general per tree, %zu nodes decoded\n",
                                  coder_name(coder), file.size(), 100.0 * (static_cast<double>(file.size()) / general.smallest() - 1.0),
                                  100.0 * (static_cast<double>(file.size()) / per_tree.smallest() - 1.0), nodes);
            }
            std::printf("\n");
        }
        std::printf("\n%s\n", note);
    }
}

}  // namespace

int main(int argc, char** argv) {
    int trees = 400, runs = 3;
    std::vector<std::string> files;
    for (int i = 1; i < argc; ++i) {
        const std::string arg = argv[i];
        if (arg == "--trees" && i + 1 < argc)
            trees = std::stoi(argv[++i]);
        else if (arg == "--runs" && i + 1 < argc)
            runs = std::max(1, std::stoi(argv[++i]));
        else if (arg == "--help" || arg == "-h") {
            std::printf("usage: encode_compression_report [--trees N (forest size, 0 = no Table 6)] [--runs K] [SKELETON.ply ...]\n");
            return 0;
        } else
            files.push_back(arg);
    }
    try {
        bool ok = true;
        std::printf(
                "# Compression of chain-coded trees (Strnad et al. 2020, §4, Experiments 2 and 3)\n\n"
                "Trees: synth::grow, leafless, seed 1, one per species of config/species.yaml; internode length l = median "
                "edge, radius unit 1 mm. Times: thread CPU time, fastest of %d runs, one thread.\n",
                runs);
        std::vector<Row5> rows;
        for (const bench::NamedTree& t : bench::table5_trees()) rows.push_back(measure_tree(t.name, t.tree, runs, ok));
        for (const std::string& file : files) rows.push_back(measure_tree(file, read_skeleton_ply(file), runs, ok));
        print_table5(rows);
        if (trees > 0) table6(bench::forest_trees(trees), runs);
        std::printf("\nRound trips exact: %s\n", ok ? "yes" : "NO");
        return ok ? 0 : 1;
    } catch (const Error& e) {
        std::fprintf(stderr, "encode_compression_report: %s\n", e.what());
        return static_cast<int>(e.code());
    }
}
