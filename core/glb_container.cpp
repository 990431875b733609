#include "core/glb_container.hpp"

#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "core/little_endian.hpp"

#include <nlohmann/json.hpp>

namespace treelobes {

namespace {

constexpr std::size_t kGlbHeaderBytes = 12, kGlbChunkHeaderBytes = 8;

std::uint32_t glb_u32(const std::string& bytes, std::size_t at) {
    return load<std::uint32_t>(reinterpret_cast<const std::uint8_t*>(bytes.data() + at));
}

}  // namespace

// Chunk padding (§4.4.3.1: each chunk starts and ends on a 4-byte boundary) is not required of a
// file: the data is read byte by byte, so a writer that forgot it still reads.
GlbContainer::GlbContainer(std::string bytes, const std::string& name) : bytes_(std::move(bytes)) {
    const std::size_t size = bytes_.size();
    if (size < kGlbHeaderBytes + kGlbChunkHeaderBytes || glb_u32(bytes_, 0) != kGlbMagic)
        throw Error::input(name, "not a glTF binary (no glTF header)");
    if (glb_u32(bytes_, 4) != 2) throw Error::input(name, "glTF binary version " + std::to_string(glb_u32(bytes_, 4)) + ", expected 2");
    if (glb_u32(bytes_, 8) != size) throw Error::input(name, "glTF binary length does not match the file size (truncated?)");
    json_offset_ = kGlbHeaderBytes + kGlbChunkHeaderBytes;
    json_length_ = glb_u32(bytes_, 12);
    if (glb_u32(bytes_, 16) != kGlbJsonChunk || json_length_ > size - json_offset_)
        throw Error::input(name, "glTF binary has no valid JSON chunk");
    // §4.4.3.3: the BIN chunk, when there is one, is the second chunk.
    const std::size_t second = json_offset_ + json_length_;
    if (size - second < kGlbChunkHeaderBytes) {
        if (second != size)
            throw Error::input(name, "glTF binary has " + std::to_string(size - second) + " stray bytes after its JSON chunk");
        return;
    }
    const std::size_t length = glb_u32(bytes_, second);
    if (length > size - second - kGlbChunkHeaderBytes)
        throw Error::input(name, "glTF binary chunk of " + std::to_string(length) + " bytes runs past the end of the file");
    if (glb_u32(bytes_, second + 4) != kGlbBinChunk) return;
    has_bin_ = true;
    bin_offset_ = second + kGlbChunkHeaderBytes;
    bin_length_ = length;
}

GlbContainer read_glb_container(const std::filesystem::path& path) { return GlbContainer(read_file(path), path.string()); }

nlohmann::json parse_glb_json(const GlbContainer& glb, const std::string& name) {
    try {
        return nlohmann::json::parse(glb.json_text());
    } catch (const nlohmann::json::exception& e) {
        throw Error::input(name, std::string("glTF JSON chunk: ") + e.what());
    }
}

}  // namespace treelobes
