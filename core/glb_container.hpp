// The GLB container of glTF 2.0 (Khronos glTF 2.0 specification §4.4 "Binary glTF Layout"): a
// 12-byte header (magic "glTF", container version 2, total length), a JSON chunk, then an
// optional BIN chunk; every chunk starts and ends on a 4-byte boundary. Shared by the `info`
// command (core/file_info.cpp) and the mesh reader (core/glb_mesh_io.cpp); the writer is
// export/gltf.cpp.
#pragma once

#include <nlohmann/json_fwd.hpp>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>

namespace treelobes {

inline constexpr std::uint32_t kGlbMagic = 0x46546C67;      // "glTF"
inline constexpr std::uint32_t kGlbJsonChunk = 0x4E4F534A;  // "JSON"
inline constexpr std::uint32_t kGlbBinChunk = 0x004E4942;   // "BIN\0"

// The whole file and where its chunks lie in it.
class GlbContainer {
public:
    // Checks the header and the chunk lengths against the file: Error(InvalidInput) naming
    // `name` for a file that is no GLB, of another container version, truncated or whose chunks
    // do not fit. Chunks after the BIN chunk are skipped (§4.4.3.1: unknown types are ignored).
    GlbContainer(std::string bytes, const std::string& name);

    std::string_view json_text() const { return std::string_view(bytes_).substr(json_offset_, json_length_); }
    bool has_bin() const { return has_bin_; }
    // The BIN chunk's payload (empty without one); it may be up to 3 bytes longer than the
    // buffer it holds (§3.6.1.2, padding).
    std::string_view bin() const { return std::string_view(bytes_).substr(bin_offset_, bin_length_); }
    std::size_t file_size() const { return bytes_.size(); }

private:
    std::string bytes_;
    std::size_t json_offset_ = 0, json_length_ = 0;
    std::size_t bin_offset_ = 0, bin_length_ = 0;
    bool has_bin_ = false;
};

GlbContainer read_glb_container(const std::filesystem::path& path);

// The JSON chunk parsed; Error(InvalidInput) "<name>: glTF JSON chunk: ..." when it is not JSON.
nlohmann::json parse_glb_json(const GlbContainer& glb, const std::string& name);

}  // namespace treelobes
