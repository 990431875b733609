#include "core/point_cloud.hpp"

#include "core/error.hpp"

#include <limits>

namespace treelobes {

const char* attribute_type_name(AttributeType type) {
    switch (type) {
        case AttributeType::UInt8:
            return "uint8";
        case AttributeType::Int8:
            return "int8";
        case AttributeType::UInt16:
            return "uint16";
        case AttributeType::Int16:
            return "int16";
        case AttributeType::UInt32:
            return "uint32";
        case AttributeType::Int32:
            return "int32";
        case AttributeType::UInt64:
            return "uint64";
        case AttributeType::Int64:
            return "int64";
        case AttributeType::Float32:
            return "float32";
        case AttributeType::Float64:
            return "float64";
    }
    return "unknown";
}

std::size_t attribute_type_size(AttributeType type) {
    switch (type) {
        case AttributeType::UInt8:
        case AttributeType::Int8:
            return 1;
        case AttributeType::UInt16:
        case AttributeType::Int16:
            return 2;
        case AttributeType::UInt32:
        case AttributeType::Int32:
        case AttributeType::Float32:
            return 4;
        case AttributeType::UInt64:
        case AttributeType::Int64:
        case AttributeType::Float64:
            return 8;
    }
    return 0;
}

const ExtraAttribute* PointCloud::extra(const std::string& name) const {
    for (const auto& attribute : extras)
        if (attribute.name == name) return &attribute;
    return nullptr;
}

ExtraAttribute* PointCloud::extra(const std::string& name) {
    for (auto& attribute : extras)
        if (attribute.name == name) return &attribute;
    return nullptr;
}

ExtraAttribute& PointCloud::add_extra(const std::string& name, AttributeType type, double fill) {
    if (ExtraAttribute* existing = extra(name)) return *existing;
    ExtraAttribute attribute;
    attribute.name = name;
    attribute.type = type;
    attribute.values.assign(size(), fill);
    extras.push_back(std::move(attribute));
    return extras.back();
}

std::vector<std::string> PointCloud::attribute_names() const {
    std::vector<std::string> names;
    if (!intensity.empty()) names.emplace_back("intensity");
    if (!return_number.empty()) names.emplace_back("return_number");
    if (!number_of_returns.empty()) names.emplace_back("number_of_returns");
    if (!classification.empty()) names.emplace_back("classification");
    if (!rgb.empty()) names.emplace_back("rgb");
    if (!gps_time.empty()) names.emplace_back("gps_time");
    for (const auto& attribute : extras) names.push_back(attribute.name);
    return names;
}

namespace {

template <typename T>
std::vector<T> pick(const std::vector<T>& values, const std::vector<std::size_t>& indices) {
    if (values.empty()) return {};
    std::vector<T> out;
    out.reserve(indices.size());
    for (std::size_t i : indices) out.push_back(values[i]);
    return out;
}

}  // namespace

PointCloud PointCloud::subset(const std::vector<std::size_t>& indices) const {
    PointCloud out;
    out.origin = origin;
    out.georef = georef;
    out.source = source;
    out.positions = pick(positions, indices);
    out.intensity = pick(intensity, indices);
    out.return_number = pick(return_number, indices);
    out.number_of_returns = pick(number_of_returns, indices);
    out.classification = pick(classification, indices);
    out.rgb = pick(rgb, indices);
    out.gps_time = pick(gps_time, indices);
    for (const auto& attribute : extras) {
        ExtraAttribute copy = attribute;
        copy.values = pick(attribute.values, indices);
        out.extras.push_back(std::move(copy));
    }
    return out;
}

PointCloud PointCloud::subset(const std::vector<bool>& keep) const {
    std::vector<std::size_t> indices;
    for (std::size_t i = 0; i < keep.size() && i < size(); ++i)
        if (keep[i]) indices.push_back(i);
    return subset(indices);
}

std::pair<Eigen::Vector3f, Eigen::Vector3f> PointCloud::bounds() const {
    if (positions.empty()) throw Error::input("", "empty point cloud has no bounds");
    Eigen::Vector3f lo = Eigen::Vector3f::Constant(std::numeric_limits<float>::max());
    Eigen::Vector3f hi = -lo;
    for (const auto& p : positions) {
        lo = lo.cwiseMin(p);
        hi = hi.cwiseMax(p);
    }
    return {lo, hi};
}

void PointCloud::check_consistent(const std::string& context) const {
    const std::size_t n = size();
    auto check = [&](std::size_t count, const std::string& name) {
        if (count != 0 && count != n)
            throw Error::input(context,
                               "attribute '" + name + "' has " + std::to_string(count) + " values for " + std::to_string(n) + " points");
    };
    check(intensity.size(), "intensity");
    check(return_number.size(), "return_number");
    check(number_of_returns.size(), "number_of_returns");
    check(classification.size(), "classification");
    check(rgb.size(), "rgb");
    check(gps_time.size(), "gps_time");
    for (const auto& attribute : extras)  // extras are never optional per point
        if (attribute.values.size() != n)
            throw Error::input(context, "attribute '" + attribute.name + "' has " + std::to_string(attribute.values.size()) +
                                                " values for " + std::to_string(n) + " points");
}

}  // namespace treelobes
