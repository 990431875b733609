#include "lobes/mesh_coder.hpp"

#include "core/error.hpp"
#include "geometry/closed_mesh.hpp"

#include <cmath>
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

std::string ByteReader::string() {
    const std::size_t n = count(1, "string length");
    std::string s(bytes_.substr(pos_, n));
    pos_ += n;
    return s;
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

void encode_mesh(const TriangleMesh& input, double quantum, ByteWriter& out) {
    TriangleMesh mesh = input;
    remove_unused_vertices(mesh);  // first-use order: a new corner is always the next index
    out.varint(mesh.vertices.size());
    out.varint(mesh.faces.size());
    std::int64_t previous[3] = {0, 0, 0};
    for (const auto& v : mesh.vertices)
        for (int k = 0; k < 3; ++k) {
            const std::int64_t q = quantize(v[k], quantum);
            out.svarint(q - previous[k]);
            previous[k] = q;
        }
    int next = 0;
    for (const auto& f : mesh.faces)
        for (int index : f) {
            if (index == next) {
                out.varint(0);
                ++next;
            } else {
                out.varint(static_cast<std::uint64_t>(next - index));
            }
        }
}

TriangleMesh decode_mesh(ByteReader& in, double quantum) {
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
