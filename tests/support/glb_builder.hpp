// Hand-made glTF 2.0 binaries for the .glb reader tests: a JSON document and the BIN chunk's
// bytes, assembled the way glTF 2.0 §4.4 lays them out (written here, not with
// core/glb_container, which the tests check).
#pragma once

#include "core/little_endian.hpp"

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace treelobes::test {

class GlbBuilder {
public:
    static constexpr int kByte = 5120, kUnsignedByte = 5121, kShort = 5122, kUnsignedShort = 5123, kUnsignedInt = 5125, kFloat = 5126;

    nlohmann::json doc = {{"asset", {{"version", "2.0"}}}, {"scene", 0}, {"scenes", {{{"nodes", nlohmann::json::array()}}}}};
    std::string bin;

    // `values` as an accessor of `type` ("SCALAR", "VEC3"), each element padded to `stride`
    // bytes when given (a bufferView byteStride); its index.
    template <typename T>
    int accessor(const std::vector<T>& values, int component_type, const std::string& type, std::size_t stride = 0,
                 bool normalized = false) {
        const std::size_t components = type == "SCALAR" ? 1 : 3;
        const std::size_t element = components * sizeof(T);
        const std::size_t offset = bin.size();
        for (std::size_t i = 0; i < values.size(); i += components) {
            for (std::size_t c = 0; c < components; ++c) {
                std::uint8_t bytes[sizeof(T)];
                store<T>(bytes, values[i + c]);
                bin.append(reinterpret_cast<const char*>(bytes), sizeof(T));
            }
            if (stride > element) bin.append(stride - element, '\0');
        }
        while (bin.size() % 4) bin += '\0';
        nlohmann::json view = {{"buffer", 0}, {"byteOffset", offset}, {"byteLength", bin.size() - offset}};
        if (stride) view["byteStride"] = stride;
        doc["bufferViews"].push_back(view);
        nlohmann::json accessor = {{"bufferView", doc["bufferViews"].size() - 1},
                                   {"componentType", component_type},
                                   {"count", values.size() / components},
                                   {"type", type}};
        if (normalized) accessor["normalized"] = true;
        doc["accessors"].push_back(accessor);
        // Updated in place: nlohmann-json 3.11.2 leaked the array it replaced when this was
        // assigned a new initializer list on every call (LeakSanitizer, clang 14).
        doc["buffers"][0]["byteLength"] = bin.size();
        return static_cast<int>(doc["accessors"].size()) - 1;
    }

    int positions(const std::vector<Eigen::Vector3f>& points) {
        std::vector<float> values;
        for (const auto& p : points) values.insert(values.end(), {p.x(), p.y(), p.z()});
        return accessor(values, kFloat, "VEC3");
    }

    // A mesh of `primitives` named `name`; its index.
    int mesh(const std::string& name, const nlohmann::json& primitives) {
        doc["meshes"].push_back({{"name", name}, {"primitives", primitives}});
        return static_cast<int>(doc["meshes"].size()) - 1;
    }

    std::string bytes() const { return container(doc.dump(), bin); }

    // Header, JSON chunk (padded with spaces), BIN chunk (padded with zeros, left out when empty).
    static std::string container(std::string json_text, std::string bin_chunk) {
        while (json_text.size() % 4) json_text += ' ';
        while (bin_chunk.size() % 4) bin_chunk += '\0';
        std::string out;
        const auto u32 = [&](std::size_t v) {
            std::uint8_t bytes[4];
            store<std::uint32_t>(bytes, static_cast<std::uint32_t>(v));
            out.append(reinterpret_cast<const char*>(bytes), 4);
        };
        u32(0x46546C67);
        u32(2);
        u32(12 + 8 + json_text.size() + (bin_chunk.empty() ? 0 : 8 + bin_chunk.size()));
        u32(json_text.size());
        u32(0x4E4F534A);
        out += json_text;
        if (!bin_chunk.empty()) {
            u32(bin_chunk.size());
            u32(0x004E4942);
            out += bin_chunk;
        }
        return out;
    }
};

}  // namespace treelobes::test
