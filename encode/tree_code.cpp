#include "encode/tree_code.hpp"

#include "core/error.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <deque>
#include <limits>
#include <numeric>
#include <sstream>

namespace treelobes::encode {

namespace {

// Beyond 2^52 a double no longer holds every integer, so Eq. 1 would not round exactly.
constexpr double kMaxVoxelsFromRoot = 4503599627370496.0;

void check_positive(double value, const char* what) {
    if (!(value > 0.0) || !std::isfinite(value))
        throw Error::usage(std::string(what) + " must be a positive number (got " + std::to_string(value) + ")");
}

// Voxel coordinates of every vertex relative to the root (Eq. 1).
std::vector<Voxel> voxelize_tree(const TreeGraph& tree, double voxel_size, const std::string& context) {
    const Eigen::Vector3d root = tree.nodes[0].position.cast<double>();
    std::vector<Voxel> voxels(tree.size());
    for (std::size_t i = 0; i < tree.size(); ++i) {
        const Eigen::Vector3d scaled = (tree.nodes[i].position.cast<double>() - root) / voxel_size;
        if (scaled.cwiseAbs().maxCoeff() > kMaxVoxelsFromRoot)
            throw Error::input(context, "node " + std::to_string(i) + " lies too far from the root for voxel size " +
                                                std::to_string(voxel_size) + " m");
        for (int axis = 0; axis < 3; ++axis) voxels[i][axis] = voxelize(scaled[axis]);
    }
    return voxels;
}

std::vector<int> quantize_radii(const TreeGraph& tree, double radius_unit, const std::string& context) {
    std::vector<int> radii(tree.size());
    for (std::size_t i = 0; i < tree.size(); ++i) {
        const float radius = tree.nodes[i].radius;
        if (radius < 0.0f) throw Error::input(context, "node " + std::to_string(i) + " has a negative radius");
        if (radius / radius_unit > std::numeric_limits<int>::max() / 2)
            throw Error::input(
                    context, "node " + std::to_string(i) + " has a radius too large for radius unit " + std::to_string(radius_unit) + " m");
        radii[i] = quantize_radius(radius, radius_unit);
    }
    return radii;
}

// Direction change 1 - cos(angle) between two moves; a zero move counts as a right angle, as
// in TreeGraph::order_children_by_subtree_length.
double turn(const Voxel& incoming, const Voxel& move) {
    const Eigen::Vector3d a = incoming.cast<double>(), b = move.cast<double>();
    if (a.isZero() || b.isZero()) return 1.0;
    return 1.0 - a.dot(b) / (a.norm() * b.norm());
}

// Children of every vertex in coding order: main child first, then laterals. Uses only what the
// code stores (quantized radii, voxel moves) plus the node index, so a decoded tree, whose
// indices follow the code order, sorts the same way.
std::vector<std::vector<int>> coding_order(const TreeGraph& tree, const std::vector<Voxel>& voxels, const std::vector<int>& radii) {
    // Incoming direction of each vertex: the last non-zero move on the path from the root, so that
    // zero-length internodes (contracted by the decoder) do not change it; +z above the root.
    std::vector<Voxel> incoming(tree.size(), Voxel(0, 0, 1));
    for (int node : tree.preorder())
        for (int child : tree.nodes[node].children) {
            const Voxel move = voxels[child] - voxels[node];
            incoming[child] = move.isZero() ? incoming[node] : move;
        }
    std::vector<std::vector<int>> order(tree.size());
    for (std::size_t node = 0; node < tree.size(); ++node) {
        std::vector<int> children = tree.nodes[node].children;
        auto key = [&](int child) {
            return std::make_tuple(-radii[child], turn(incoming[node], Voxel(voxels[child] - voxels[node])), child);
        };
        std::sort(children.begin(), children.end(), [&](int a, int b) { return key(a) < key(b); });
        order[node] = std::move(children);
    }
    return order;
}

// Nodes whose internode the decoder would read as a multi-way fork code (contracted_internodes):
// the first vertex of a branch (a child of the root, or a lateral in coding order) that lies
// in its parent's voxel and is not a tip.
std::vector<bool> nodes_read_as_forks(const TreeGraph& tree, const std::vector<Voxel>& voxels, const std::vector<std::vector<int>>& order) {
    std::vector<bool> read_as_fork(tree.size(), false);
    for (std::size_t node = 0; node < tree.size(); ++node)
        for (int child : order[node]) {
            const bool branch_start = node == 0 || child != order[node][0];
            read_as_fork[child] = branch_start && voxels[child] == voxels[node] && !tree.nodes[child].children.empty();
        }
    return read_as_fork;
}

// The tree without the `dropped` nodes, their children attached to the nearest kept ancestor.
// Kept nodes keep their relative order (coding_order breaks ties by index); `source` (node ->
// input node) is updated alike.
TreeGraph without_nodes(const TreeGraph& tree, const std::vector<bool>& dropped, std::vector<int>& source) {
    std::vector<int> index(tree.size(), -1);
    std::vector<int> kept_source;
    for (std::size_t i = 0; i < tree.size(); ++i)
        if (!dropped[i]) {
            index[i] = static_cast<int>(kept_source.size());
            kept_source.push_back(source[i]);
        }
    TreeGraph out;
    out.origin = tree.origin;
    out.nodes.resize(kept_source.size());
    for (std::size_t i = 0; i < tree.size(); ++i) {
        if (dropped[i]) continue;
        TreeNode& node = out.nodes[static_cast<std::size_t>(index[i])];
        node.position = tree.nodes[i].position;
        node.radius = tree.nodes[i].radius;
        int parent = tree.nodes[i].parent;
        while (parent >= 0 && dropped[static_cast<std::size_t>(parent)]) parent = tree.nodes[static_cast<std::size_t>(parent)].parent;
        node.parent = parent < 0 ? -1 : index[static_cast<std::size_t>(parent)];
        if (node.parent >= 0) out.nodes[static_cast<std::size_t>(node.parent)].children.push_back(index[i]);
    }
    source = std::move(kept_source);
    return out;
}

// Pseudocode 1 with the multi-way fork rule: builds the internode stream of one tree.
class StreamBuilder {
public:
    StreamBuilder(const TreeGraph& tree, const std::vector<Voxel>& voxels, const std::vector<int>& radii,
                  std::vector<std::vector<int>> order)
            : tree_(tree), voxels_(voxels), radii_(radii), order_(std::move(order)) {}

    // Returns the stream; `sources` receives the tree node behind each internode (-1 for the
    // zero-length internodes of forks).
    std::vector<Internode> build(std::vector<int>& sources) {
        const std::vector<int>& root_children = order_[0];
        if (root_children.size() > 1) {
            // The root forks at once: a zero-length root internode carries the fork.
            emit(Voxel::Zero(), kFork, radii_[root_children[0]], -1);
            queue_.push_back({0, std::vector<int>(root_children.begin() + 1, root_children.end())});
        }
        walk_branch(root_children[0]);
        while (!queue_.empty()) {
            const LateralGroup group = std::move(queue_.front());
            queue_.pop_front();
            start_lateral(group);
        }
        sources = std::move(sources_);
        return std::move(stream_);
    }

private:
    // Laterals of one fork vertex still to be coded, in coding order.
    struct LateralGroup {
        int fork = 0;
        std::vector<int> laterals;
    };

    void emit(const Voxel& move, char terminator, int radius, int source) {
        stream_.push_back({move, terminator, radius});
        sources_.push_back(source);
    }

    // Follows main children from `node` (the first child vertex of a branch) to the branch tip.
    void walk_branch(int node) {
        for (;;) {
            const std::vector<int>& children = order_[node];
            const char terminator = children.empty() ? kTip : children.size() == 1 ? kEndOfInternode : kFork;
            emit(voxels_[node] - voxels_[tree_.nodes[node].parent], terminator, radii_[node], node);
            if (children.empty()) return;
            if (children.size() > 1) queue_.push_back({node, std::vector<int>(children.begin() + 1, children.end())});
            node = children[0];
        }
    }

    // Dequeued lateral(s) of a fork: the siblings of a multi-way fork are announced by
    // zero-length internodes ("7 6...6") and queued singly, then the first lateral is coded.
    void start_lateral(const LateralGroup& group) {
        const int first = group.laterals[0];
        for (std::size_t k = 1; k < group.laterals.size(); ++k) {
            emit(Voxel::Zero(), kFork, radii_[first], -1);
            queue_.push_back({group.fork, {group.laterals[k]}});
        }
        walk_branch(first);
    }

    const TreeGraph& tree_;
    const std::vector<Voxel>& voxels_;
    const std::vector<int>& radii_;
    const std::vector<std::vector<int>> order_;  // owned: callers pass a temporary
    std::deque<LateralGroup> queue_;
    std::vector<Internode> stream_;
    std::vector<int> sources_;
};

// Tree node behind each decoded node: the root, then every internode that the decoder does not
// contract, in code order.
std::vector<int> decoded_sources(const std::vector<Internode>& stream, const std::vector<int>& sources) {
    const std::vector<bool> contracted = contracted_internodes(stream);
    std::vector<int> decoded{0};
    for (std::size_t i = 0; i < stream.size(); ++i)
        if (!contracted[i]) decoded.push_back(sources[i]);
    return decoded;
}

// Pseudocode 1 backwards, one internode at a time: the tree building shared by decode_tree
// (internodes parsed from the symbol text) and decode_internodes (internodes straight from a
// stream decoder). Checks every value a corrupt code could make unsafe; the caller checks the
// structure (check_symbols, or the queue at every tip).
class TreeBuilder {
public:
    TreeBuilder(const CodeGeometry& geometry, CodeKind kind, std::size_t internodes, const std::string& context)
            : geometry_(geometry), root_(geometry.root_position.cast<double>()), kind_(kind), context_(context) {
        check_positive(geometry.voxel_size, "voxel size");
        check_positive(geometry.radius_unit, "radius unit");
        if (geometry.root_radius < 0) throw Error::input(context, "root radius is negative");
        tree_.origin = geometry.origin;
        tree_.nodes.reserve(internodes + 1);
        tree_.add_node(geometry.root_position, static_cast<float>(geometry.root_radius * geometry.radius_unit), -1);
        voxels_.reserve(internodes + 1);
        voxels_.push_back(Voxel::Zero());
    }

    // Adds internode `index` (0-based) with the vector its moves add up to; `describe` names it
    // in the error for a move beyond kMaxVoxelCoordinate.
    template <class Describe>
    void add(std::size_t index, const Voxel& vector, char terminator, int radius, Describe describe) {
        const Voxel move = differential_base_ ? Voxel(previous_ + vector) : vector;
        if (radius < 0)
            throw Error::input(context_, "radius " + std::to_string(index + 1) + " is negative (" + std::to_string(radius) + ")");
        if (move.cwiseAbs().maxCoeff() > kMaxVoxelCoordinate)
            throw Error::input(context_, describe() + " moves more than 2^40 voxels (corrupt code)");
        // contracted_internodes: a leading zero move of a branch that does not end it.
        const bool contracted = branch_start_ && move.isZero() && terminator != kTip;
        if (!contracted) {
            const Voxel voxel = voxels_[static_cast<std::size_t>(attach_)] + move;
            if (voxel.cwiseAbs().maxCoeff() > kMaxVoxelCoordinate)
                throw Error::input(context_,
                                   "internode " + std::to_string(index + 1) + " ends more than 2^40 voxels from the root (corrupt code)");
            const Eigen::Vector3d position = root_ + voxel.cast<double>() * geometry_.voxel_size;
            attach_ = add_child(position.cast<float>(), static_cast<float>(radius * geometry_.radius_unit));
            voxels_.push_back(voxel);
            branch_start_ = terminator == kTip;
        }
        if (terminator == kFork) queued_forks_.push_back(attach_);
        if (terminator == kTip && next_fork_ < queued_forks_.size()) attach_ = queued_forks_[next_fork_++];
        previous_ = move;
        differential_base_ = kind_ == CodeKind::DBF6 && terminator != kTip;
    }

    // Laterals announced by a 6 and not started yet.
    std::size_t open_forks() const { return queued_forks_.size() - next_fork_; }
    TreeGraph take() { return std::move(tree_); }

private:
    // TreeGraph::add_node for the valid parent attach_ (node indices follow the code order),
    // inlined: the out-of-line call with its parent check costs ~3 ms of the forest's ~130.
    int add_child(const Eigen::Vector3f& position, float radius) {
        const int index = static_cast<int>(tree_.nodes.size());
        TreeNode& node = tree_.nodes.emplace_back();
        node.position = position;
        node.radius = radius;
        node.parent = attach_;
        auto& siblings = tree_.nodes[static_cast<std::size_t>(attach_)].children;
        siblings.push_back(index);
        return index;
    }

    const CodeGeometry& geometry_;
    const Eigen::Vector3d root_;
    const CodeKind kind_;
    const std::string& context_;
    TreeGraph tree_;
    std::vector<Voxel> voxels_;      // voxel of every vertex added so far
    std::vector<int> queued_forks_;  // FIFO: vertices whose next lateral is still to come
    std::size_t next_fork_ = 0;
    int attach_ = 0;  // vertex the next internode starts from
    Voxel previous_ = Voxel::Zero();
    bool differential_base_ = false;  // DBF6: the internode codes a correction of `previous_`
    bool branch_start_ = true;        // no vertex of the current branch decoded yet
};

}  // namespace

std::int64_t voxelize(double coordinate_in_voxels) {
    const double x = coordinate_in_voxels;
    const double sign = x > 0.0 ? 1.0 : x < 0.0 ? -1.0 : 0.0;
    return static_cast<std::int64_t>(std::trunc(x + 0.5 * sign));
}

int quantize_radius(float radius, double radius_unit) { return static_cast<int>(std::round(static_cast<double>(radius) / radius_unit)); }

namespace {

constexpr std::string_view kCodeComment = "treelobes_code";

// Shortest decimal that reads back as the same double.
std::string exact_decimal(double value) {
    char text[32];
    const auto end = std::to_chars(text, text + sizeof text, value).ptr;
    return {text, end};
}

}  // namespace

std::string code_parameters_comment(const CodeParameters& p) {
    return std::string(kCodeComment) + " resolution " + exact_decimal(p.resolution) + " internode_length " +
           exact_decimal(p.internode_length) + " radius_unit " + exact_decimal(p.radius_unit);
}

std::optional<CodeParameters> find_code_parameters(const std::vector<std::string>& comments, const std::string& context) {
    for (const std::string& comment : comments) {
        std::istringstream words(comment);
        std::string keyword, r, l, u;
        CodeParameters p;
        if (!(words >> keyword) || keyword != kCodeComment) continue;
        if (!(words >> r >> p.resolution >> l >> p.internode_length >> u >> p.radius_unit) || r != "resolution" ||
            l != "internode_length" || u != "radius_unit" || !(std::isfinite(p.resolution) && p.resolution > 0) ||
            !(std::isfinite(p.internode_length) && p.internode_length > 0) || !(std::isfinite(p.radius_unit) && p.radius_unit > 0))
            throw Error::input(context, "malformed header comment '" + comment +
                                                "', expected 'treelobes_code resolution R internode_length L radius_unit U'");
        return p;
    }
    return std::nullopt;
}

double median_internode_length(const TreeGraph& tree, const std::string& context) {
    std::vector<float> lengths;
    for (std::size_t i = 1; i < tree.size(); ++i)
        if (const float length = tree.edge_length(static_cast<int>(i)); length > 0.0f) lengths.push_back(length);
    if (lengths.empty()) throw Error::input(context, "no edge of positive length: cannot derive the internode length");
    const auto middle = lengths.begin() + static_cast<std::ptrdiff_t>(lengths.size() / 2);
    std::nth_element(lengths.begin(), middle, lengths.end());
    return *middle;
}

EncodedTree encode_tree(const TreeGraph& tree, const EncodeOptions& options, const std::string& context) {
    check_positive(options.resolution, "resolution");
    check_positive(options.radius_unit, "radius unit");
    if (options.internode_length != 0.0) check_positive(options.internode_length, "internode length");
    tree.validate(context);
    if (tree.nodes[0].children.empty()) throw Error::input(context, "tree has no internodes (the root has no child)");

    EncodedTree encoded;
    encoded.resolution = options.resolution;
    encoded.internode_length = options.internode_length > 0.0 ? options.internode_length : median_internode_length(tree, context);
    encoded.geometry.voxel_size = encoded.internode_length / options.resolution;  // Eq. 2
    encoded.geometry.radius_unit = options.radius_unit;
    encoded.geometry.root_position = tree.nodes[0].position;
    encoded.geometry.origin = tree.origin;

    // A vertex that a decoder would merge into its parent (its internode reads as a fork code) is
    // merged before coding, repeatedly (the merge can put the next vertex of the branch in the
    // same place): the code then decodes to exactly the tree it codes, and encoding the decoded
    // tree gives the same code again.
    TreeGraph coded = tree;
    std::vector<int> input_node(tree.size());
    std::iota(input_node.begin(), input_node.end(), 0);
    std::vector<Voxel> voxels;
    std::vector<int> radii;
    std::vector<std::vector<int>> order;
    for (;;) {
        voxels = voxelize_tree(coded, encoded.geometry.voxel_size, context);
        radii = quantize_radii(coded, options.radius_unit, context);
        order = coding_order(coded, voxels, radii);
        const std::vector<bool> merged = nodes_read_as_forks(coded, voxels, order);
        if (std::find(merged.begin(), merged.end(), true) == merged.end()) break;
        coded = without_nodes(coded, merged, input_node);
    }
    encoded.geometry.root_radius = radii[0];

    std::vector<int> sources;
    encoded.internodes = StreamBuilder(coded, voxels, radii, std::move(order)).build(sources);
    encoded.decoded_to_source = decoded_sources(encoded.internodes, sources);
    for (int& node : encoded.decoded_to_source)
        if (node >= 0) node = input_node[static_cast<std::size_t>(node)];
    encoded.code.kind = options.kind;
    encoded.code.symbols = write_symbols(encoded.internodes, options.kind);
    encoded.code.radii.reserve(encoded.internodes.size());
    for (const Internode& internode : encoded.internodes) encoded.code.radii.push_back(internode.radius);
    return encoded;
}

TreeGraph decode_tree(const ChainCode& code, const CodeGeometry& geometry, const std::string& context) {
    check_positive(geometry.voxel_size, "voxel size");
    check_positive(geometry.radius_unit, "radius unit");
    const std::size_t count = check_symbols(code.symbols, context);
    if (code.radii.size() != count)  // read_internodes's checks and messages, inlined below
        throw Error::input(context, "radius list has " + std::to_string(code.radii.size()) + " values but the " +
                                            code_kind_name(code.kind) + " code has " + std::to_string(count) +
                                            " internodes (one radius per 6, 7 or 8)");
    // One pass over the symbols, without an intermediate internode stream (read_internodes and
    // contracted_internodes do the same in two more passes).
    TreeBuilder builder(geometry, code.kind, count, context);
    Voxel delta = Voxel::Zero();
    std::size_t index = 0;
    for (std::size_t s = 0; s < code.symbols.size(); ++s) {
        const char symbol = code.symbols[s];
        if (symbol < kFork) {  // a move 0..5 (check_symbols admits nothing else below 6)
            delta[(symbol - '0') % 3] += symbol < '3' ? 1 : -1;
            continue;
        }
        builder.add(index, delta, symbol, code.radii[index], [&] { return "internode ending at character " + std::to_string(s + 1); });
        delta.setZero();
        ++index;
    }
    return builder.take();
}

TreeGraph decode_internodes(const InternodeVectors& code, const CodeGeometry& geometry, const std::string& context) {
    const std::size_t count = code.terminators.size();
    if (code.vectors.size() != count || code.radii.size() != count)
        throw Error::input(context, "radius list has " + std::to_string(code.radii.size()) + " values but the " +
                                            code_kind_name(code.kind) + " code has " + std::to_string(count) +
                                            " internodes (one radius per 6, 7 or 8)");
    if (count == 0 || code.terminators.back() != kTip) throw Error::input(context, "chain code ends without the final branch tip 7");
    TreeBuilder builder(geometry, code.kind, count, context);
    for (std::size_t i = 0; i < count; ++i) {
        const char terminator = code.terminators[i];
        if (terminator != kFork && terminator != kTip && terminator != kEndOfInternode)
            throw Error::input(context, "internode " + std::to_string(i + 1) + " has no valid terminator");
        // check_symbols's rules: every 7 but the last returns to a queued lateral, and the last
        // one leaves none.
        if (terminator == kTip && i + 1 < count && builder.open_forks() == 0)
            throw Error::input(context, "tip 7 of internode " + std::to_string(i + 1) +
                                                " ends the last open branch but the code goes on (a fork 6 is missing)");
        if (i + 1 == count && builder.open_forks() > 0)
            throw Error::input(context, std::to_string(builder.open_forks()) +
                                                " fork(s) 6 without a lateral branch: the code ends before every queued lateral was coded");
        builder.add(i, code.vectors[i], terminator, code.radii[i], [&] { return "internode " + std::to_string(i + 1); });
    }
    return builder.take();
}

}  // namespace treelobes::encode
