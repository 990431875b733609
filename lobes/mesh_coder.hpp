// Compact byte coding for the .tlobe file (docs/tlobe.md): LEB128 varints, zigzag signed
// varints, little-endian floats, and a lossless-after-quantization triangle mesh coder.
//
// Mesh coding (version 4): the faces are visited by crossing edges, depth first from a first face
// (Rossignac's Edgebreaker order [Rossignac 1999]), so each new face shares an edge with one
// already coded and only its third vertex is coded, as one of: a vertex not seen before (its
// position a residual from the parallelogram prediction), the vertex beside the shared edge on
// the border of the faces coded so far (left or right), or an earlier vertex by back-reference.
// On a closed lobe surface nearly every face is one of the first three, about 2 bits after
// deflate, against 17 bits for the vertex indices of version 3. Vertex positions are quantized
// to a grid of `quantum` metres in the tree's frame. The whole .tlobe payload is deflated
// afterwards.
#pragma once

#include "core/triangle_mesh.hpp"

#include <cstdint>
#include <string>
#include <string_view>

namespace treelobes::lobes {

class ByteWriter {
public:
    void u8(std::uint8_t v) { bytes_.push_back(static_cast<char>(v)); }
    void varint(std::uint64_t v);
    void svarint(std::int64_t v) { varint((static_cast<std::uint64_t>(v) << 1) ^ static_cast<std::uint64_t>(v >> 63)); }
    void f32(float v);
    void f64(double v);
    void string(std::string_view s);
    const std::string& bytes() const { return bytes_; }

private:
    std::string bytes_;
};

// Reads what ByteWriter wrote; every overrun or malformed value throws Error(InvalidInput)
// naming `context` (the file).
class ByteReader {
public:
    ByteReader(std::string_view bytes, std::string context) : bytes_(bytes), context_(std::move(context)) {}
    std::uint8_t u8();
    std::uint64_t varint();
    std::int64_t svarint() {
        const std::uint64_t v = varint();
        return static_cast<std::int64_t>(v >> 1) ^ -static_cast<std::int64_t>(v & 1);
    }
    // `base` plus a delta (svarint): the next coordinate of a delta-coded sequence. The writer's
    // grid coordinates are int32 (quantize), so a result outside that range is a damaged file,
    // refused before the sum can overflow.
    std::int64_t delta_coordinate(std::int64_t base);
    float f32();
    double f64();
    std::string string();
    // The next `size` bytes (checked to be there), skipped.
    std::string_view take(std::size_t size);
    // A reader of `bytes` (a part of this one's) that names the same context in its errors.
    ByteReader part(std::string_view bytes) const { return ByteReader(bytes, context_); }
    // A count that must be plausible for the bytes left (each item takes >= `min_bytes`).
    std::size_t count(std::size_t min_bytes, const char* what);
    bool at_end() const { return pos_ == bytes_.size(); }
    [[noreturn]] void fail(const std::string& what) const;

private:
    std::string_view bytes_;
    std::size_t pos_ = 0;
    std::string context_;
};

// Integer grid coordinate of a value (round to nearest); throws Error(Usage) if out of int32 range.
std::int64_t quantize(double value, double quantum);

// The mesh's vertices are taken in its local frame (its origin is not stored). Any triangle
// mesh codes; the decoded one has the same faces and positions (within half a quantum), with
// faces in traversal order and vertices numbered in order of first use (unused ones dropped).
void encode_mesh(const TriangleMesh& mesh, double quantum, ByteWriter& out);
TriangleMesh decode_mesh(ByteReader& in, double quantum);
// The mesh coding of version 3 files (vertex index per corner), which this build still reads.
TriangleMesh decode_mesh_v3(ByteReader& in, double quantum);

}  // namespace treelobes::lobes
