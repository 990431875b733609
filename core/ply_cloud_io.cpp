// Point clouds as PLY: the `vertex` element with x y z (float or double, any property order)
// and scalar fields. CloudCompare writes and reads per-point scalar fields as `scalar_<name>`;
// we read both `scalar_<name>` and bare names and write `scalar_<name>`.
#include "core/attribute_value.hpp"
#include "core/cloud_io.hpp"
#include "core/error.hpp"
#include "core/georef_sidecar.hpp"
#include "core/log.hpp"
#include "core/ply_format.hpp"

#include <algorithm>
#include <cmath>

namespace fs = std::filesystem;

namespace treelobes {

namespace {

std::string lower(std::string s) {
    std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return s;
}

std::string strip_scalar_prefix(const std::string& name) { return lower(name).starts_with("scalar_") ? name.substr(7) : name; }

bool is_coordinate(const std::string& name) { return name == "x" || name == "y" || name == "z"; }

template <typename T>
std::vector<T> cast_values(const std::vector<double>& values, const std::vector<std::size_t>& kept) {
    std::vector<T> out;
    out.reserve(kept.size());
    for (std::size_t i : kept) out.push_back(attribute_value<T>(values[i]));
    return out;
}

// Maps one PLY scalar property onto the cloud's attributes.
void store_property(const ply::Property& p, const std::vector<std::size_t>& kept, PointCloud& cloud,
                    std::vector<const ply::Property*>& colour) {
    const std::string base = lower(strip_scalar_prefix(p.name));
    if (base == "red" || base == "r")
        colour[0] = &p;
    else if (base == "green" || base == "g")
        colour[1] = &p;
    else if (base == "blue" || base == "b")
        colour[2] = &p;
    else if (base == "intensity")
        cloud.intensity = cast_values<std::uint16_t>(p.values, kept);
    else if (base == "classification")
        cloud.classification = cast_values<std::uint8_t>(p.values, kept);
    else if (base == "return_number")
        cloud.return_number = cast_values<std::uint8_t>(p.values, kept);
    else if (base == "number_of_returns")
        cloud.number_of_returns = cast_values<std::uint8_t>(p.values, kept);
    else if (base == "gps_time") {
        for (std::size_t i : kept) cloud.gps_time.push_back(p.values[i]);
    } else {
        ExtraAttribute attribute;
        attribute.name = strip_scalar_prefix(p.name);
        attribute.type = p.type;
        for (std::size_t i : kept) attribute.values.push_back(p.values[i]);
        cloud.extras.push_back(std::move(attribute));
    }
}

void store_colour(const std::vector<const ply::Property*>& colour, const std::vector<std::size_t>& kept, PointCloud& cloud) {
    if (!colour[0] || !colour[1] || !colour[2]) return;
    for (std::size_t i : kept)
        cloud.rgb.push_back({attribute_value<std::uint16_t>(colour[0]->values[i]), attribute_value<std::uint16_t>(colour[1]->values[i]),
                             attribute_value<std::uint16_t>(colour[2]->values[i])});
}

ply::Property scalar(const std::string& name, AttributeType type, std::vector<double> values) {
    ply::Property p;
    p.name = name;
    p.type = type;
    p.values = std::move(values);
    return p;
}

template <typename T>
std::vector<double> as_doubles(const std::vector<T>& values) {
    return std::vector<double>(values.begin(), values.end());
}

}  // namespace

PointCloud read_ply_cloud(const fs::path& path) {
    const std::string name = path.string();
    const ply::File file = ply::read(path);
    const ply::Element* vertex = file.find("vertex");
    if (!vertex) throw Error::input(name, "PLY has no 'vertex' element");
    const ply::Property* axis[3] = {vertex->find("x"), vertex->find("y"), vertex->find("z")};
    if (!axis[0] || !axis[1] || !axis[2]) throw Error::input(name, "PLY vertex element lacks x, y or z");
    for (const auto* a : axis)
        if (a->is_list) throw Error::input(name, "PLY x/y/z must be scalar properties");

    PointCloud cloud;
    cloud.source.format = "ply";
    cloud.source.version = file.format;
    std::vector<std::size_t> kept;
    kept.reserve(vertex->count);
    for (std::size_t i = 0; i < vertex->count; ++i) {
        const Eigen::Vector3d p(axis[0]->values[i], axis[1]->values[i], axis[2]->values[i]);
        if (p.allFinite()) kept.push_back(i);
    }
    if (kept.empty()) throw Error::input(name, vertex->count ? "all points have NaN/inf coordinates" : "PLY has no vertices");

    // Our writers store local coordinates plus an origin comment. Other files may hold
    // georeferenced doubles: then the origin is taken from the data so that float local
    // coordinates keep their precision.
    const auto stored_origin = read_origin_comment(file.comments);
    Eigen::Vector3d shift = Eigen::Vector3d::Zero();
    if (!stored_origin) {
        const std::size_t first = kept.front();
        for (int k = 0; k < 3; ++k)
            if (std::abs(axis[k]->values[first]) >= 1e4) shift[k] = std::round(axis[k]->values[first] / 1000.0) * 1000.0;
    }
    cloud.origin = stored_origin ? *stored_origin : shift;
    cloud.positions.reserve(kept.size());
    for (std::size_t i : kept)
        cloud.positions.push_back((Eigen::Vector3d(axis[0]->values[i], axis[1]->values[i], axis[2]->values[i]) - shift).cast<float>());

    std::vector<const ply::Property*> colour(3, nullptr);
    for (const auto& p : vertex->properties)
        if (!p.is_list && !is_coordinate(p.name)) store_property(p, kept, cloud, colour);
    store_colour(colour, kept, cloud);

    cloud.source.dropped_non_finite = vertex->count - kept.size();
    if (cloud.source.dropped_non_finite)
        log_warn(name + ": dropped " + std::to_string(cloud.source.dropped_non_finite) + " point(s) with NaN/inf coordinates");
    return cloud;
}

void write_ply_cloud(const PointCloud& cloud, const fs::path& path, bool binary) {
    cloud.check_consistent(path.string());
    ply::File file;
    file.format = binary ? "binary_little_endian" : "ascii";
    file.comments.push_back("generated by treelobes");
    write_origin_comment(cloud.origin, file.comments);

    ply::Element vertex;
    vertex.name = "vertex";
    vertex.count = cloud.size();
    for (int k = 0; k < 3; ++k) {
        std::vector<double> values(cloud.size());
        for (std::size_t i = 0; i < cloud.size(); ++i) values[i] = cloud.positions[i][k];
        vertex.properties.push_back(scalar(std::string(1, "xyz"[k]), AttributeType::Float32, std::move(values)));
    }
    if (!cloud.rgb.empty()) {
        const bool eight_bit =
                std::all_of(cloud.rgb.begin(), cloud.rgb.end(), [](const auto& c) { return c[0] < 256 && c[1] < 256 && c[2] < 256; });
        for (int c = 0; c < 3; ++c) {
            std::vector<double> values;
            for (const auto& colour : cloud.rgb) values.push_back(colour[c]);
            vertex.properties.push_back(scalar(c == 0   ? "red"
                                               : c == 1 ? "green"
                                                        : "blue",
                                               eight_bit ? AttributeType::UInt8 : AttributeType::UInt16, std::move(values)));
        }
    }
    if (!cloud.intensity.empty())
        vertex.properties.push_back(scalar("scalar_intensity", AttributeType::UInt16, as_doubles(cloud.intensity)));
    if (!cloud.return_number.empty())
        vertex.properties.push_back(scalar("scalar_return_number", AttributeType::UInt8, as_doubles(cloud.return_number)));
    if (!cloud.number_of_returns.empty())
        vertex.properties.push_back(scalar("scalar_number_of_returns", AttributeType::UInt8, as_doubles(cloud.number_of_returns)));
    if (!cloud.classification.empty())
        vertex.properties.push_back(scalar("scalar_classification", AttributeType::UInt8, as_doubles(cloud.classification)));
    if (!cloud.gps_time.empty()) vertex.properties.push_back(scalar("scalar_gps_time", AttributeType::Float64, cloud.gps_time));
    for (const auto& attribute : cloud.extras)
        vertex.properties.push_back(scalar("scalar_" + attribute.name, attribute.type, attribute.values));
    file.elements.push_back(std::move(vertex));
    ply::write(file, path);
    write_georef_sidecar(path, cloud.origin, cloud.georef);
}

}  // namespace treelobes
