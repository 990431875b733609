// Triangle meshes (core/mesh_io.cpp): our OBJ and glb readers, OpenMesh for the others. The first
// byte picks the format, so one corpus covers OBJ, OFF, STL (ascii and binary), PLY and glTF
// binary (.glb).
#include "core/mesh_io.hpp"
#include "fuzz_support.hpp"

#include <array>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    if (size == 0) return 0;
    static constexpr std::array<const char*, 5> kExtensions{"obj", "off", "stl", "ply", "glb"};
    const std::string extension = kExtensions[data[0] % kExtensions.size()];
    const auto path = treelobes::fuzz::input_file(treelobes::fuzz::as_text(data + 1, size - 1), extension);
    treelobes::fuzz::expect_only_input_errors([&] { treelobes::read_mesh(path); });
    return 0;
}
