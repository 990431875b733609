#include "lobes/mesh_coder.hpp"

#include "core/error.hpp"
#include "geometry/closed_mesh.hpp"

#include <cmath>
#include <optional>
#include <unordered_map>
#include <unordered_set>
#include <cstring>
#include <limits>

namespace treelobes::lobes {

void ByteWriter::varint(std::uint64_t v) {
    while (v >= 0x80) {
        u8(static_cast<std::uint8_t>(v | 0x80));
        v >>= 7;
    }
    u8(static_cast<std::uint8_t>(v));
}

// Little-endian on every host: bytes are assembled explicitly.
void ByteWriter::f32(float v) {
    std::uint32_t bits;
    std::memcpy(&bits, &v, 4);
    for (int i = 0; i < 4; ++i) u8(static_cast<std::uint8_t>(bits >> (8 * i)));
}

void ByteWriter::f64(double v) {
    std::uint64_t bits;
    std::memcpy(&bits, &v, 8);
    for (int i = 0; i < 8; ++i) u8(static_cast<std::uint8_t>(bits >> (8 * i)));
}

void ByteWriter::string(std::string_view s) {
    varint(s.size());
    bytes_.append(s);
}

void ByteReader::fail(const std::string& what) const {
    throw Error::input(context_, what + " (at payload byte " + std::to_string(pos_) + ")");
}

std::uint8_t ByteReader::u8() {
    if (pos_ >= bytes_.size()) fail("truncated payload");
    return static_cast<std::uint8_t>(bytes_[pos_++]);
}

std::uint64_t ByteReader::varint() {
    std::uint64_t v = 0;
    for (int shift = 0; shift < 64; shift += 7) {
        const std::uint8_t b = u8();
        v |= static_cast<std::uint64_t>(b & 0x7f) << shift;
        if (!(b & 0x80)) return v;
    }
    fail("malformed varint");
}

std::int64_t ByteReader::delta_coordinate(std::int64_t base) {
    constexpr std::int64_t kMax = std::numeric_limits<std::int32_t>::max(), kMin = std::numeric_limits<std::int32_t>::min();
    const std::int64_t delta = svarint();
    if (delta < kMin - kMax || delta > kMax - kMin) fail("coordinate delta out of range");
    const std::int64_t value = base + delta;
    if (value < kMin || value > kMax) fail("coordinate out of range");
    return value;
}

float ByteReader::f32() {
    std::uint32_t bits = 0;
    for (int i = 0; i < 4; ++i) bits |= static_cast<std::uint32_t>(u8()) << (8 * i);
    float v;
    std::memcpy(&v, &bits, 4);
    return v;
}

double ByteReader::f64() {
    std::uint64_t bits = 0;
    for (int i = 0; i < 8; ++i) bits |= static_cast<std::uint64_t>(u8()) << (8 * i);
    double v;
    std::memcpy(&v, &bits, 8);
    return v;
}

std::string ByteReader::string() { return std::string(take(count(1, "string length"))); }

std::string_view ByteReader::take(std::size_t size) {
    if (size > bytes_.size() - pos_) fail("truncated section");
    const std::string_view part = bytes_.substr(pos_, size);
    pos_ += size;
    return part;
}

std::size_t ByteReader::count(std::size_t min_bytes, const char* what) {
    const std::uint64_t n = varint();
    if (n > (bytes_.size() - pos_) / std::max<std::size_t>(min_bytes, 1)) fail(std::string("implausible ") + what);
    return static_cast<std::size_t>(n);
}

std::int64_t quantize(double value, double quantum) {
    const double q = std::round(value / quantum);
    if (!(std::abs(q) < static_cast<double>(std::numeric_limits<std::int32_t>::max())))
        throw Error::usage("tlobe: coordinate " + std::to_string(value) + " does not fit the quantization grid");
    return static_cast<std::int64_t>(q);
}

namespace {

enum Corner : std::uint8_t { kNewVertex = 0, kLeftNeighbour = 1, kRightNeighbour = 2, kEarlierVertex = 3, kNoFace = 4 };

std::uint64_t half_edge_key(int from, int to) {
    return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(from)) << 32) | static_cast<std::uint32_t>(to);
}

// What encoder and decoder both know while faces are added in traversal order (docs/tlobe.md):
// the half-edges of the faces added so far, the gates still to cross, and per vertex the
// open half-edges (those whose reverse is not added yet) that end or start at it. Both sides run
// this same state machine, so every symbol means the same to both.
class Traversal {
public:
    struct Gate {
        int from, to, apex;  // half-edge from -> to of an added face whose third vertex is apex
    };

    explicit Traversal(std::size_t vertices) : into_(vertices), out_of_(vertices) {}

    void add_face(int a, int b, int c) {
        faces.push_back({a, b, c});
        for (const auto& [u, v] : {std::pair{a, b}, std::pair{b, c}, std::pair{c, a}}) {
            added_.insert(half_edge_key(u, v));
            into_[v].push_back(u);
            out_of_[u].push_back(v);
        }
    }
    // A component's first face: all three edges are gates, the first one popped first.
    void start_component() {
        const auto [a, b, c] = faces.back();
        gates_.push_back({c, a, b});
        gates_.push_back({b, c, a});
        gates_.push_back({a, b, c});
    }
    // The face (to, from, c) across a gate: its two other edges become gates, from -> c first.
    void cross(const Gate& g, int c) {
        add_face(g.to, g.from, c);
        gates_.push_back({c, g.to, g.from});
        gates_.push_back({g.from, c, g.to});
    }
    // The next gate whose reverse half-edge no added face has yet; none when the stack is empty.
    std::optional<Gate> next_gate() {
        while (!gates_.empty()) {
            const Gate g = gates_.back();
            gates_.pop_back();
            if (!added_.contains(half_edge_key(g.to, g.from))) return g;
        }
        return std::nullopt;
    }
    // The vertex before `from` on the open border (the latest-added open half-edge x -> from) and
    // the one after `to` (the latest-added open to -> y); -1 when there is none. Where the face
    // across closes the border on either side, its third vertex is one of these. (x is never
    // `to`: to -> from would be the gate's reverse, which next_gate() has found not added.)
    // Closed half-edges stay closed, so they are dropped as they are met: every entry is passed
    // over at most once, and a damaged file's fans cannot make the lookups quadratic.
    int left_of(const Gate& g) {
        return latest_open(into_[g.from], [&](int x) { return half_edge_key(g.from, x); });
    }
    int right_of(const Gate& g) {
        return latest_open(out_of_[g.to], [&](int y) { return half_edge_key(y, g.to); });
    }

    std::vector<std::array<int, 3>> faces;

private:
    // The last of `partners` whose half-edge is still open (its reverse, `reverse_key`, not added).
    template <class ReverseKey>
    int latest_open(std::vector<int>& partners, ReverseKey reverse_key) const {
        while (!partners.empty() && added_.contains(reverse_key(partners.back()))) partners.pop_back();
        return partners.empty() ? -1 : partners.back();
    }

    std::unordered_set<std::uint64_t> added_;
    std::vector<std::vector<int>> into_, out_of_;
    std::vector<Gate> gates_;
};

// The three sections of a coded mesh, each deflated well on its own: one byte per corner
// symbol, back-references to earlier vertices, and position residuals.
struct MeshSections {
    std::size_t vertices = 0;  // those the faces use
    ByteWriter symbols, references, residuals;
};

using GridPoint = std::array<std::int64_t, 3>;

GridPoint parallelogram(const GridPoint& a, const GridPoint& b, const GridPoint& apex) {
    return {a[0] + b[0] - apex[0], a[1] + b[1] - apex[1], a[2] + b[2] - apex[2]};
}

class MeshEncoder {
public:
    MeshEncoder(const TriangleMesh& mesh, double quantum) : mesh_(mesh), traversal_(mesh.vertices.size()) {
        grid_.reserve(mesh.vertices.size());
        for (const auto& v : mesh.vertices) grid_.push_back({quantize(v[0], quantum), quantize(v[1], quantum), quantize(v[2], quantum)});
        for (std::size_t f = 0; f < mesh.faces.size(); ++f)
            for (int k = 0; k < 3; ++k) faces_with_.emplace(half_edge_key(mesh.faces[f][k], mesh.faces[f][(k + 1) % 3]), f);
        coded_.assign(mesh.faces.size(), false);
        number_.assign(mesh.vertices.size(), -1);
    }

    MeshSections run() {
        for (std::size_t f = 0; f < mesh_.faces.size(); ++f) {
            if (coded_[f]) continue;
            code_start_face(f);
            while (remaining_ > 0) {
                const auto gate = traversal_.next_gate();
                if (!gate) break;
                code_face_across(*gate);
            }
        }
        out_.vertices = original_.size();
        return std::move(out_);
    }

private:
    void code_start_face(std::size_t f) {
        coded_[f] = true;
        --remaining_;
        std::array<int, 3> local{};
        for (int k = 0; k < 3; ++k) {
            const int v = mesh_.faces[f][k];
            local[k] = is_new(v) ? introduce(v, previous_) : refer(v);
        }
        traversal_.add_face(local[0], local[1], local[2]);
        traversal_.start_component();
    }

    void code_face_across(const Traversal::Gate& gate) {
        const int from = original_[gate.from], to = original_[gate.to];
        const auto face = uncoded_face_with(to, from);
        if (!face) {
            out_.symbols.u8(kNoFace);
            return;
        }
        coded_[*face] = true;
        --remaining_;
        const auto& corners = mesh_.faces[*face];
        int at = 0;
        while (!(corners[at] == to && corners[(at + 1) % 3] == from)) ++at;
        const int c = corners[(at + 2) % 3];
        int local;
        if (is_new(c)) {
            local = introduce(c, parallelogram(grid_[from], grid_[to], grid_[original_[gate.apex]]));
        } else if (number_[c] == traversal_.left_of(gate)) {
            out_.symbols.u8(kLeftNeighbour);
            local = number_[c];
        } else if (number_[c] == traversal_.right_of(gate)) {
            out_.symbols.u8(kRightNeighbour);
            local = number_[c];
        } else {
            local = refer(c);
        }
        traversal_.cross(gate, local);
    }

    // The first face not coded yet that holds the half-edge from -> to.
    std::optional<std::size_t> uncoded_face_with(int from, int to) const {
        std::optional<std::size_t> first;
        const auto [begin, end] = faces_with_.equal_range(half_edge_key(from, to));
        for (auto it = begin; it != end; ++it)
            if (!coded_[it->second] && (!first || it->second < *first)) first = it->second;
        return first;
    }

    bool is_new(int v) const { return number_[v] < 0; }

    int introduce(int v, const GridPoint& predicted) {
        out_.symbols.u8(kNewVertex);
        for (int k = 0; k < 3; ++k) out_.residuals.svarint(grid_[v][k] - predicted[k]);
        number_[v] = static_cast<int>(original_.size());
        original_.push_back(v);
        previous_ = grid_[v];
        return number_[v];
    }

    int refer(int v) {
        out_.symbols.u8(kEarlierVertex);
        out_.references.varint(static_cast<std::uint64_t>(static_cast<int>(original_.size()) - 1 - number_[v]));
        return number_[v];
    }

    const TriangleMesh& mesh_;
    Traversal traversal_;
    std::vector<GridPoint> grid_;
    std::unordered_multimap<std::uint64_t, std::size_t> faces_with_;
    std::vector<bool> coded_;
    std::vector<int> number_;    // original vertex -> number in order of introduction (-1: not yet)
    std::vector<int> original_;  // number -> original vertex
    GridPoint previous_{0, 0, 0};
    std::size_t remaining_ = mesh_.faces.size();
    MeshSections out_;
};

void write_section(const ByteWriter& section, ByteWriter& out) {
    out.varint(section.bytes().size());
    for (char b : section.bytes()) out.u8(static_cast<std::uint8_t>(b));
}

std::string_view read_section(ByteReader& in) {
    const std::size_t size = in.count(1, "mesh section size");
    return in.take(size);
}

class MeshDecoder {
public:
    MeshDecoder(std::size_t vertices, std::size_t faces, double quantum, std::string_view symbols, std::string_view references,
                std::string_view residuals, const ByteReader& context)
            : vertices_(vertices),
              faces_(faces),
              quantum_(quantum),
              traversal_(vertices),
              symbols_(context.part(symbols)),
              references_(context.part(references)),
              residuals_(context.part(residuals)) {}

    TriangleMesh run() {
        while (traversal_.faces.size() < faces_) {
            decode_start_face();
            while (traversal_.faces.size() < faces_) {
                const auto gate = traversal_.next_gate();
                if (!gate) break;
                decode_face_across(*gate);
            }
        }
        if (grid_.size() != vertices_) symbols_.fail("mesh has vertices no face uses");
        if (!symbols_.at_end() || !references_.at_end() || !residuals_.at_end()) symbols_.fail("trailing bytes in a lobe mesh");
        TriangleMesh mesh;
        mesh.vertices.reserve(grid_.size());
        for (const auto& q : grid_)
            mesh.vertices.emplace_back(static_cast<float>(static_cast<double>(q[0]) * quantum_),
                                       static_cast<float>(static_cast<double>(q[1]) * quantum_),
                                       static_cast<float>(static_cast<double>(q[2]) * quantum_));
        mesh.faces = std::move(traversal_.faces);
        return mesh;
    }

private:
    void decode_start_face() {
        std::array<int, 3> local{};
        for (int& v : local) {
            const std::uint8_t symbol = symbols_.u8();
            if (symbol == kNewVertex)
                v = introduce(grid_.empty() ? GridPoint{0, 0, 0} : grid_.back());
            else if (symbol == kEarlierVertex)
                v = earlier_vertex();
            else
                symbols_.fail("invalid corner symbol of a lobe mesh's first face");
        }
        traversal_.add_face(local[0], local[1], local[2]);
        traversal_.start_component();
    }

    void decode_face_across(const Traversal::Gate& gate) {
        int c = -1;
        switch (symbols_.u8()) {
            case kNoFace:
                return;
            case kNewVertex:
                c = introduce(parallelogram(grid_[gate.from], grid_[gate.to], grid_[gate.apex]));
                break;
            case kLeftNeighbour:
                c = traversal_.left_of(gate);
                break;
            case kRightNeighbour:
                c = traversal_.right_of(gate);
                break;
            case kEarlierVertex:
                c = earlier_vertex();
                break;
            default:
                symbols_.fail("invalid corner symbol in a lobe mesh");
        }
        if (c < 0) symbols_.fail("lobe mesh refers to a border neighbour that does not exist");
        traversal_.cross(gate, c);
    }

    int introduce(const GridPoint& predicted) {
        if (grid_.size() >= vertices_) symbols_.fail("mesh face refers to a vertex beyond the vertex count");
        grid_.push_back({residuals_.delta_coordinate(predicted[0]), residuals_.delta_coordinate(predicted[1]),
                         residuals_.delta_coordinate(predicted[2])});
        return static_cast<int>(grid_.size()) - 1;
    }

    int earlier_vertex() {
        const std::uint64_t back = references_.varint();
        if (back >= grid_.size()) references_.fail("mesh face refers to a vertex before the first");
        return static_cast<int>(grid_.size() - 1 - back);
    }

    std::size_t vertices_, faces_;
    double quantum_;
    Traversal traversal_;
    ByteReader symbols_, references_, residuals_;
    std::vector<GridPoint> grid_;
};

}  // namespace

void encode_mesh(const TriangleMesh& mesh, double quantum, ByteWriter& out) {
    const MeshSections sections = MeshEncoder(mesh, quantum).run();
    out.varint(sections.vertices);
    out.varint(mesh.faces.size());
    write_section(sections.symbols, out);
    write_section(sections.references, out);
    write_section(sections.residuals, out);
}

TriangleMesh decode_mesh(ByteReader& in, double quantum) {
    const std::uint64_t vertices = in.varint(), faces = in.varint();
    const std::string_view symbols = read_section(in), references = read_section(in), residuals = read_section(in);
    // Every face takes at least one symbol byte, and a face brings at most 3 vertices.
    if (faces > symbols.size() || vertices > 3 * faces) in.fail("implausible lobe mesh size");
    return MeshDecoder(vertices, faces, quantum, symbols, references, residuals, in).run();
}

TriangleMesh decode_mesh_v3(ByteReader& in, double quantum) {
    TriangleMesh mesh;
    const std::size_t vertices = in.count(3, "vertex count");
    const std::size_t faces = in.count(3, "face count");
    mesh.vertices.reserve(vertices);
    mesh.faces.reserve(faces);
    std::int64_t q[3] = {0, 0, 0};
    for (std::size_t i = 0; i < vertices; ++i) {
        Eigen::Vector3f p;
        for (int k = 0; k < 3; ++k) {
            q[k] = in.delta_coordinate(q[k]);
            p[k] = static_cast<float>(static_cast<double>(q[k]) * quantum);
        }
        mesh.vertices.push_back(p);
    }
    int next = 0;
    for (std::size_t i = 0; i < faces; ++i) {
        std::array<int, 3> f{};
        for (int& index : f) {
            const std::uint64_t code = in.varint();
            if (code == 0) {
                if (static_cast<std::size_t>(next) >= vertices) in.fail("mesh face refers to a vertex beyond the vertex count");
                index = next++;
            } else {
                if (code > static_cast<std::uint64_t>(next)) in.fail("mesh face refers to a vertex before the first");
                index = next - static_cast<int>(code);
            }
        }
        mesh.faces.push_back(f);
    }
    if (static_cast<std::size_t>(next) != vertices) in.fail("mesh has vertices no face uses");
    return mesh;
}

}  // namespace treelobes::lobes
