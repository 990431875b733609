#include "encode/forest_file.hpp"

#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "core/parallel.hpp"
#include "encode/coder_best.hpp"

#include <Eigen/Geometry>

#include <cstring>

namespace treelobes::encode {

namespace {

constexpr char kForestMagic[4] = {'D', 'B', 'F', 'F'};
constexpr std::size_t kHeaderBytes = 4 + 1 + 4 + 4 + 3 * 8;
constexpr std::size_t kMaxNameBytes = 4096;

}  // namespace

std::vector<std::uint8_t> write_forest_bytes(const std::vector<ForestTree>& trees, const TreeFileOptions& options, ForestStats* stats) {
    if (trees.size() > kMaxForestTrees) throw Error::usage("too many trees for one .forest file");
    std::vector<StoredTree> stored(trees.size());
    std::vector<std::exception_ptr> errors(trees.size());
    auto rethrow_first = [&errors] {  // the first failing tree, whatever the scheduling
        for (const auto& error : errors)
            if (error) std::rethrow_exception(error);
    };
    treelobes::parallel_for(std::size_t{0}, trees.size(), [&](std::size_t i) {
        try {
            stored[i] = store_tree(trees[i].skeleton, options, trees[i].name.empty() ? "tree " + std::to_string(i) : trees[i].name);
        } catch (...) {
            errors[i] = std::current_exception();
        }
    });
    rethrow_first();
    auto encode_records = [&](const BestPrior* prior, std::vector<std::vector<std::uint8_t>>& records,
                              std::vector<std::vector<StreamSizes>>& sizes) {
        records.assign(trees.size(), {});
        sizes.assign(trees.size(), {});
        treelobes::parallel_for(std::size_t{0}, trees.size(), [&](std::size_t i) {
            try {
                records[i] = write_tree_record(stored[i], &sizes[i], prior);
            } catch (...) {
                errors[i] = std::current_exception();
            }
        });
        rethrow_first();
        std::size_t total = 0;
        for (const auto& record : records) total += record.size();
        return total;
    };
    std::vector<std::vector<std::uint8_t>> records;
    std::vector<std::vector<StreamSizes>> sizes;
    const std::size_t plain_total = encode_records(nullptr, records, sizes);
    // Coder best: a model prior trained on every code of the forest (in file order), kept when
    // it saves more than its own size (it does for many similar trees, not for a few).
    std::vector<std::uint8_t> prior_bytes;
    if (options.coder == Coder::Best && !trees.empty()) {
        std::vector<const ChainCode*> codes;
        for (const StoredTree& t : stored)
            for (const ChainCode& code : t.lods) codes.push_back(&code);
        const BestPrior prior = BestPrior::train(codes);
        std::vector<std::uint8_t> candidate = prior.serialize();
        std::vector<std::vector<std::uint8_t>> prior_records;
        std::vector<std::vector<StreamSizes>> prior_sizes;
        if (encode_records(&prior, prior_records, prior_sizes) + candidate.size() < plain_total) {
            prior_bytes = std::move(candidate);
            records = std::move(prior_records);
            sizes = std::move(prior_sizes);
        }
    }
    Eigen::Vector3d origin = Eigen::Vector3d::Zero();
    if (!trees.empty()) {
        origin = trees.front().position;
        for (const ForestTree& t : trees) origin = origin.cwiseMin(t.position);
    }
    std::vector<std::uint8_t> index;
    put_varint(index, prior_bytes.size());
    index.insert(index.end(), prior_bytes.begin(), prior_bytes.end());
    for (std::size_t i = 0; i < trees.size(); ++i) {
        const ForestTree& t = trees[i];
        if (!t.position.allFinite() || !std::isfinite(t.azimuth))
            throw Error::input(t.name.empty() ? "tree " + std::to_string(i) : t.name, "position or azimuth is not finite");
        if (t.name.size() > kMaxNameBytes) throw Error::usage("tree name longer than " + std::to_string(kMaxNameBytes) + " bytes");
        put_varint(index, records[i].size());
        for (int a = 0; a < 3; ++a) put_f32(index, static_cast<float>(t.position[a] - origin[a]));
        put_f32(index, t.azimuth);
        put_varint(index, t.name.size());
        index.insert(index.end(), t.name.begin(), t.name.end());
    }
    std::vector<std::uint8_t> out(std::begin(kForestMagic), std::end(kForestMagic));
    out.push_back(kForestFileVersion);
    put_u32(out, static_cast<std::uint32_t>(trees.size()));
    put_u32(out, static_cast<std::uint32_t>(index.size()));
    for (int a = 0; a < 3; ++a) put_f64(out, origin[a]);
    out.insert(out.end(), index.begin(), index.end());
    put_u32(out, crc32_of(out));
    if (stats) {
        stats->header_and_index = out.size();
        stats->trees = std::move(sizes);
    }
    for (const auto& record : records) {
        out.insert(out.end(), record.begin(), record.end());
        put_u32(out, crc32_of(record));
    }
    return out;
}

void write_forest_file(const std::vector<ForestTree>& trees, const TreeFileOptions& options, const std::filesystem::path& path,
                       ForestStats* stats) {
    const std::vector<std::uint8_t> bytes = write_forest_bytes(trees, options, stats);
    write_file_atomically(path, std::string(bytes.begin(), bytes.end()));
}

// Takes the skeleton by value: decoders move their fresh tree in, so no node is copied.
TreeGraph place_tree(TreeGraph skeleton, const ForestEntry& entry) {
    const Eigen::Matrix3d rotation = Eigen::AngleAxisd(entry.azimuth, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    // The tree's own origin (its root position in its frame) turns with it; the local offsets
    // stay small floats.
    skeleton.origin = entry.position + rotation * skeleton.origin;
    const Eigen::Matrix3f r = rotation.cast<float>();
    for (TreeNode& node : skeleton.nodes) node.position = r * node.position;
    return skeleton;
}

ForestReader::ForestReader(const std::filesystem::path& path) : context_(path.string()) {
    if (std::filesystem::is_directory(path)) throw Error::input(context_, "is a directory, not a .forest file");
    file_.open(path, std::ios::binary);
    if (!file_) throw Error::input(context_, "cannot open file");
    file_.seekg(0, std::ios::end);
    const auto file_size = static_cast<std::uint64_t>(file_.tellg());
    file_.seekg(0);
    std::vector<std::uint8_t> head(std::min<std::uint64_t>(file_size, kHeaderBytes));
    file_.read(reinterpret_cast<char*>(head.data()), static_cast<std::streamsize>(head.size()));
    if (head.size() >= kHeaderBytes) {
        ByteReader in(head, 4 + 1 + 4, context_);
        const std::uint64_t index_size = in.u32();
        if (index_size + kHeaderBytes + 4 <= file_size) {  // else parse_index reports the truncation
            head.resize(kHeaderBytes + index_size + 4);
            file_.read(reinterpret_cast<char*>(head.data() + kHeaderBytes), static_cast<std::streamsize>(index_size + 4));
        }
    }
    if (!file_) throw Error::input(context_, "read error");
    parse_index(head, file_size);
}

ForestReader::ForestReader(std::vector<std::uint8_t> bytes, std::string context)
        : context_(std::move(context)), memory_(std::move(bytes)), in_memory_(true) {
    parse_index(memory_, memory_.size());
}

void ForestReader::parse_index(std::span<const std::uint8_t> head, std::uint64_t file_size) {
    if (head.size() < 4 || std::memcmp(head.data(), kForestMagic, 4) != 0)
        throw Error::input(context_, "not a .forest file (no DBFF magic)");
    ByteReader in(head, 4, context_);
    const std::uint8_t version = in.u8();
    if (version != kForestFileVersion)
        throw Error::input(context_, "unsupported .forest version " + std::to_string(version) + " (this build reads " +
                                             std::to_string(kForestFileVersion) + ")");
    const std::uint32_t count = in.u32();
    const std::uint32_t index_size = in.u32();
    if (static_cast<std::uint64_t>(kHeaderBytes) + index_size + 4 > head.size())
        throw Error::input(context_, "truncated .forest file (the index ends beyond the file)");
    const std::size_t index_end = kHeaderBytes + index_size;
    ByteReader crc(head, index_end, context_);
    if (crc.u32() != crc32_of(head.first(index_end)))
        throw Error::input(context_, "checksum mismatch in the header or index: the .forest file is corrupt");
    if (count > kMaxForestTrees || count > index_size) throw Error::input(context_, "invalid tree count " + std::to_string(count));
    for (int a = 0; a < 3; ++a) origin_[a] = in.f64();
    std::uint64_t offset = index_end + 4;
    entries_.resize(count);
    ByteReader index(head.first(index_end), kHeaderBytes, context_);
    const std::uint64_t prior_size = index.varint();
    if (prior_size > index.remaining()) index.fail("truncated model prior");
    const auto prior_bytes = index.take(prior_size);
    if (prior_size > 0) prior_ = std::make_shared<BestPrior>(BestPrior::deserialize(prior_bytes, context_));
    for (ForestEntry& e : entries_) {
        e.size = index.varint();
        e.offset = offset;
        if (e.size > file_size || offset + e.size + 4 > file_size)
            throw Error::input(context_, "truncated .forest file (tree records end beyond the file)");
        offset += e.size + 4;
        Eigen::Vector3f delta;
        for (int a = 0; a < 3; ++a) delta[a] = index.f32();
        e.position = origin_ + delta.cast<double>();
        e.azimuth = index.f32();
        const std::uint64_t name_size = index.varint();
        if (name_size > kMaxNameBytes) index.fail("invalid tree name length");
        const auto name = index.take(name_size);
        e.name.assign(name.begin(), name.end());
    }
    if (index.remaining() != 0) throw Error::input(context_, "unexpected bytes after the index");
    if (offset != file_size) throw Error::input(context_, "unexpected bytes after the last tree record");
    index_end_ = index_end + 4;
}

const ForestEntry& ForestReader::entry(std::size_t i) const {
    if (i >= entries_.size())
        throw Error::usage(context_ + " has " + std::to_string(entries_.size()) + " trees (0.." +
                           std::to_string(entries_.size() == 0 ? 0 : entries_.size() - 1) + "), not tree " + std::to_string(i));
    return entries_[i];
}

std::vector<std::uint8_t> ForestReader::record_bytes(std::size_t i) {
    const ForestEntry& e = entry(i);
    std::vector<std::uint8_t> bytes(e.size + 4);
    if (in_memory_) {
        std::memcpy(bytes.data(), memory_.data() + e.offset, bytes.size());
    } else {
        file_.clear();
        file_.seekg(static_cast<std::streamoff>(e.offset));
        file_.read(reinterpret_cast<char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
        if (!file_) throw Error::input(context_, "read error in tree " + std::to_string(i));
    }
    ByteReader crc(bytes, e.size, context_);
    if (crc.u32() != crc32_of(std::span<const std::uint8_t>(bytes).first(e.size)))
        throw Error::input(context_, "checksum mismatch in tree " + std::to_string(i) + ": the record is corrupt");
    bytes.resize(e.size);
    return bytes;
}

StoredTree ForestReader::read(std::size_t i, int lod, std::vector<StreamSizes>* sizes) {
    const std::vector<std::uint8_t> bytes = record_bytes(i);
    std::size_t position = 0;
    const std::string context = context_ + ": tree " + std::to_string(i);
    StoredTree tree = read_tree_record(bytes, position, lod, context, sizes, prior_.get());
    if (position != bytes.size()) throw Error::input(context, "unexpected bytes after the tree record");
    return tree;
}

TreeGraph ForestReader::decode(std::size_t i, int lod) {
    const std::vector<std::uint8_t> bytes = record_bytes(i);
    std::size_t position = 0;
    const std::string context = context_ + ": tree " + std::to_string(i);
    TreeGraph skeleton = decode_tree_record(bytes, position, lod, context, prior_.get());
    if (position != bytes.size()) throw Error::input(context, "unexpected bytes after the tree record");
    return place_tree(std::move(skeleton), entry(i));
}

}  // namespace treelobes::encode
