#include "encode/tree_file.hpp"

#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "encode/lod.hpp"

#include <zlib.h>

#include <bit>
#include <cmath>
#include <cstring>

namespace treelobes::encode {

namespace {

constexpr char kTreeFileMagic[4] = {'D', 'B', 'F', '6'};

// Record flags: which optional fields follow.
enum RecordFlag : std::uint8_t { kHasRootPosition = 1, kUsesPrior = 2 };

bool finite_positive(double v) { return std::isfinite(v) && v > 0.0; }

}  // namespace

CodeGeometry StoredTree::geometry() const {
    CodeGeometry g;
    g.voxel_size = internode_length / resolution;  // Eq. 2
    g.radius_unit = radius_unit;
    g.root_radius = root_radius;
    g.root_position = Eigen::Vector3f::Zero();
    g.origin = root_position;
    return g;
}

std::uint32_t crc32_of(std::span<const std::uint8_t> bytes) {
    uLong crc = crc32(0L, Z_NULL, 0);
    // zlib takes uInt lengths: feed large inputs in pieces.
    for (std::size_t done = 0; done < bytes.size();) {
        const std::size_t piece = std::min<std::size_t>(bytes.size() - done, 1u << 30);
        crc = crc32(crc, bytes.data() + done, static_cast<uInt>(piece));
        done += piece;
    }
    return static_cast<std::uint32_t>(crc);
}

void put_u32(std::vector<std::uint8_t>& out, std::uint32_t v) {
    for (int i = 0; i < 4; ++i) out.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
}

void put_f32(std::vector<std::uint8_t>& out, float v) { put_u32(out, std::bit_cast<std::uint32_t>(v)); }

void put_f64(std::vector<std::uint8_t>& out, double v) {
    const auto bits = std::bit_cast<std::uint64_t>(v);
    for (int i = 0; i < 8; ++i) out.push_back(static_cast<std::uint8_t>(bits >> (8 * i)));
}

void put_varint(std::vector<std::uint8_t>& out, std::uint64_t v) {
    while (v >= 0x80) {
        out.push_back(static_cast<std::uint8_t>(v | 0x80));
        v >>= 7;
    }
    out.push_back(static_cast<std::uint8_t>(v));
}

void ByteReader::fail(const std::string& what) const { throw Error::input(context_, what); }

std::span<const std::uint8_t> ByteReader::take(std::size_t count) {
    if (count > remaining())
        fail("truncated file (needs " + std::to_string(count) + " more bytes at byte " + std::to_string(position_) + ")");
    const auto piece = bytes_.subspan(position_, count);
    position_ += count;
    return piece;
}

std::uint8_t ByteReader::u8() { return take(1)[0]; }

std::uint32_t ByteReader::u32() {
    const auto b = take(4);
    return static_cast<std::uint32_t>(b[0]) | static_cast<std::uint32_t>(b[1]) << 8 | static_cast<std::uint32_t>(b[2]) << 16 |
           static_cast<std::uint32_t>(b[3]) << 24;
}

float ByteReader::f32() { return std::bit_cast<float>(u32()); }

double ByteReader::f64() {
    const std::uint64_t low = u32();
    const std::uint64_t high = u32();
    return std::bit_cast<double>(low | high << 32);
}

std::uint64_t ByteReader::varint() {
    std::uint64_t v = 0;
    for (unsigned shift = 0; shift < 64; shift += 7) {
        const std::uint8_t byte = u8();
        v |= static_cast<std::uint64_t>(byte & 0x7F) << shift;
        if (!(byte & 0x80)) return v;
    }
    fail("invalid variable-length integer");
}

StoredTree store_tree(const TreeGraph& tree, const TreeFileOptions& options, const std::string& context) {
    if (options.lods < 1 || options.lods > kMaxLods)
        throw Error::usage("--lods must be 1.." + std::to_string(kMaxLods) + " (got " + std::to_string(options.lods) + ")");
    const EncodedTree encoded = encode_tree(tree, options.encode, context);
    StoredTree stored;
    stored.kind = options.encode.kind;
    stored.coder = options.coder;
    stored.resolution = encoded.resolution;
    stored.internode_length = encoded.internode_length;
    stored.radius_unit = encoded.geometry.radius_unit;
    stored.root_position = encoded.geometry.origin + encoded.geometry.root_position.cast<double>();
    stored.root_radius = encoded.geometry.root_radius;
    const std::vector<double> thresholds = lod_thresholds(branch_thicknesses(encoded.code), options.lods);
    for (double t : thresholds) stored.thresholds.push_back(static_cast<int>(t));  // radii values: integral
    stored.lods = lod_chain(encoded.code, thresholds, context);
    return stored;
}

std::vector<std::uint8_t> write_tree_record(const StoredTree& tree, std::vector<StreamSizes>* sizes, const BestPrior* prior) {
    if (tree.lods.empty() || tree.lods.size() > kMaxLods || tree.thresholds.size() + 1 != tree.lods.size())
        throw Error(ExitCode::Internal, "tree record: LOD count and thresholds disagree");
    std::vector<std::uint8_t> out;
    out.push_back(static_cast<std::uint8_t>(tree.kind == CodeKind::F6 ? 0 : 1));
    out.push_back(static_cast<std::uint8_t>(tree.coder));
    const bool has_root = !tree.root_position.isZero();
    if (tree.coder != Coder::Best) prior = nullptr;
    out.push_back(static_cast<std::uint8_t>((has_root ? kHasRootPosition : 0) | (prior ? kUsesPrior : 0)));
    put_f64(out, tree.resolution);
    put_f64(out, tree.internode_length);
    put_f64(out, tree.radius_unit);
    if (has_root)
        for (int a = 0; a < 3; ++a) put_f64(out, tree.root_position[a]);
    put_varint(out, static_cast<std::uint64_t>(tree.root_radius));
    put_varint(out, tree.lods.size());
    for (int t : tree.thresholds) put_varint(out, static_cast<std::uint64_t>(std::max(t, 0)));
    if (sizes) sizes->clear();
    for (const ChainCode& code : tree.lods) {
        const CodedStreams streams = encode_streams(code, tree.coder, "chain code", prior);
        put_varint(out, streams.symbols.size());
        put_varint(out, streams.radii.size());
        out.insert(out.end(), streams.symbols.begin(), streams.symbols.end());
        out.insert(out.end(), streams.radii.begin(), streams.radii.end());
        if (sizes) sizes->push_back({streams.symbols.size(), streams.radii.size(), code.symbols.size(), code.radii.size()});
    }
    return out;
}

namespace {

// read_tree_record; with `internodes`, LOD `lod` is decoded into it instead of tree.lods[lod].
StoredTree parse_tree_record(std::span<const std::uint8_t> bytes, std::size_t& position, int lod, const std::string& context,
                             std::vector<StreamSizes>* sizes, const BestPrior* prior, InternodeVectors* internodes) {
    ByteReader in(bytes, position, context);
    StoredTree tree;
    const std::uint8_t kind = in.u8();
    if (kind > 1) in.fail("unknown code kind " + std::to_string(kind));
    tree.kind = kind == 0 ? CodeKind::F6 : CodeKind::DBF6;
    const std::uint8_t coder = in.u8();
    if (coder != static_cast<std::uint8_t>(Coder::Interpolative) && coder != static_cast<std::uint8_t>(Coder::Best))
        in.fail("unknown coder " + std::to_string(coder));
    tree.coder = static_cast<Coder>(coder);
    const std::uint8_t flags = in.u8();
    if (flags & ~(kHasRootPosition | kUsesPrior)) in.fail("unknown record flags " + std::to_string(flags));
    if ((flags & kUsesPrior) && (!prior || tree.coder != Coder::Best))
        in.fail("the tree record was coded with a forest's model prior, which is missing here");
    tree.resolution = in.f64();
    tree.internode_length = in.f64();
    tree.radius_unit = in.f64();
    if (!finite_positive(tree.resolution) || !finite_positive(tree.internode_length) || !finite_positive(tree.radius_unit))
        in.fail("resolution, internode length and radius unit must be positive");
    if (flags & kHasRootPosition)
        for (int a = 0; a < 3; ++a) tree.root_position[a] = in.f64();
    if (!tree.root_position.allFinite()) in.fail("root position is not finite");
    const std::uint64_t root_radius = in.varint();
    if (root_radius > INT32_MAX) in.fail("root radius out of range");
    tree.root_radius = static_cast<int>(root_radius);
    const std::uint64_t lods = in.varint();
    if (lods < 1 || lods > kMaxLods) in.fail("invalid LOD count " + std::to_string(lods));
    if (lod >= static_cast<int>(lods))
        throw Error::usage(context + " stores " + std::to_string(lods) + " LODs (0.." + std::to_string(lods - 1) + "), not LOD " +
                           std::to_string(lod));
    for (std::uint64_t k = 1; k < lods; ++k) {
        const std::uint64_t t = in.varint();
        if (t > INT32_MAX) in.fail("LOD threshold out of range");
        tree.thresholds.push_back(static_cast<int>(t));
    }
    if (sizes) sizes->clear();
    tree.lods.resize(lods);
    for (std::uint64_t k = 0; k < lods; ++k) {
        const std::uint64_t symbol_bytes = in.varint(), radii_bytes = in.varint();
        if (symbol_bytes > in.remaining() || radii_bytes > in.remaining() - symbol_bytes)
            in.fail("truncated file (LOD " + std::to_string(k) + " streams end beyond it)");
        const auto symbols = in.take(symbol_bytes);
        const auto radii = in.take(radii_bytes);
        tree.lods[k].kind = tree.kind;
        if (internodes && static_cast<int>(k) == lod) {
            *internodes = decode_stream_internodes(symbols, radii, tree.coder, tree.kind, context + ": LOD " + std::to_string(k),
                                                   (flags & kUsesPrior) ? prior : nullptr);
        } else if (lod < 0 || static_cast<int>(k) == lod) {
            tree.lods[k] = decode_streams(symbols, radii, tree.coder, tree.kind, context + ": LOD " + std::to_string(k),
                                          (flags & kUsesPrior) ? prior : nullptr);
            if (sizes) sizes->push_back({symbol_bytes, radii_bytes, tree.lods[k].symbols.size(), tree.lods[k].radii.size()});
        } else if (sizes) {
            sizes->push_back({symbol_bytes, radii_bytes, 0, 0});
        }
    }
    position = in.position();
    return tree;
}

}  // namespace

StoredTree read_tree_record(std::span<const std::uint8_t> bytes, std::size_t& position, int lod, const std::string& context,
                            std::vector<StreamSizes>* sizes, const BestPrior* prior) {
    return parse_tree_record(bytes, position, lod, context, sizes, prior, nullptr);
}

TreeGraph decode_tree_record(std::span<const std::uint8_t> bytes, std::size_t& position, int lod, const std::string& context,
                             const BestPrior* prior) {
    if (lod < 0) throw Error::usage(context + ": LOD " + std::to_string(lod) + " does not exist");
    InternodeVectors code;
    const StoredTree tree = parse_tree_record(bytes, position, lod, context, nullptr, prior, &code);
    return decode_internodes(code, tree.geometry(), context + ": LOD " + std::to_string(lod));
}

std::vector<std::uint8_t> write_tree_file_bytes(const StoredTree& tree, std::vector<StreamSizes>* sizes) {
    std::vector<std::uint8_t> out(std::begin(kTreeFileMagic), std::end(kTreeFileMagic));
    out.push_back(kTreeFileVersion);
    const std::vector<std::uint8_t> record = write_tree_record(tree, sizes);
    out.insert(out.end(), record.begin(), record.end());
    put_u32(out, crc32_of(out));
    return out;
}

StoredTree read_tree_file_bytes(std::span<const std::uint8_t> bytes, int lod, const std::string& context, std::vector<StreamSizes>* sizes) {
    if (bytes.size() < 4 || std::memcmp(bytes.data(), kTreeFileMagic, 4) != 0)
        throw Error::input(context, "not a .dbf6 file (no DBF6 magic)");
    if (bytes.size() < 4 + 1 + 4) throw Error::input(context, "truncated .dbf6 file");
    if (bytes[4] != kTreeFileVersion)
        throw Error::input(context, "unsupported .dbf6 version " + std::to_string(bytes[4]) + " (this build reads " +
                                            std::to_string(kTreeFileVersion) + ")");
    // The checksum comes first: a corrupt or truncated file is reported as such, not as whatever
    // the damaged bytes would decode to.
    const auto body = bytes.first(bytes.size() - 4);
    ByteReader trailer(bytes, bytes.size() - 4, context);
    if (trailer.u32() != crc32_of(body)) throw Error::input(context, "checksum mismatch: the .dbf6 file is corrupt or truncated");
    std::size_t position = 5;
    StoredTree tree = read_tree_record(body, position, lod, context, sizes);
    if (position != body.size()) throw Error::input(context, "unexpected bytes after the tree record");
    return tree;
}

void write_tree_file(const StoredTree& tree, const std::filesystem::path& path, std::vector<StreamSizes>* sizes) {
    const std::vector<std::uint8_t> bytes = write_tree_file_bytes(tree, sizes);
    write_file_atomically(path, std::string(bytes.begin(), bytes.end()));
}

StoredTree read_tree_file(const std::filesystem::path& path, int lod, std::vector<StreamSizes>* sizes) {
    const std::string contents = read_file(path);
    const std::span<const std::uint8_t> bytes(reinterpret_cast<const std::uint8_t*>(contents.data()), contents.size());
    return read_tree_file_bytes(bytes, lod, path.string(), sizes);
}

TreeGraph decode_stored_tree(const StoredTree& tree, int lod, const std::string& context) {
    if (lod < 0 || lod >= static_cast<int>(tree.lods.size()))
        throw Error::usage(context + " stores " + std::to_string(tree.lods.size()) + " LODs, not LOD " + std::to_string(lod));
    return decode_tree(tree.lods[static_cast<std::size_t>(lod)], tree.geometry(), context + ": LOD " + std::to_string(lod));
}

}  // namespace treelobes::encode
