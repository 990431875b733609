// Generic PLY (ascii, binary little/big endian) reading and writing: the one PLY parser of
// the project, used by the point-cloud and skeleton readers/writers. Values are held as double
// per property; list properties (e.g. faces) are kept as lists.
#pragma once

#include "core/point_cloud.hpp"  // AttributeType

#include <filesystem>
#include <string>
#include <vector>

namespace treelobes::ply {

struct Property {
    std::string name;
    AttributeType type = AttributeType::Float32;
    bool is_list = false;
    AttributeType count_type = AttributeType::UInt8;  // list length type
    std::vector<double> values;                       // scalar property: one per element item
    std::vector<std::vector<double>> lists;           // list property: one list per item
};

struct Element {
    std::string name;
    std::size_t count = 0;
    std::vector<Property> properties;
    const Property* find(const std::string& property) const;
};

struct File {
    std::string format = "binary_little_endian";  // or "ascii", "binary_big_endian"
    std::vector<std::string> comments;
    std::vector<Element> elements;
    const Element* find(const std::string& element) const;
};

// Throws Error(InvalidInput) naming the file for malformed headers, truncated bodies, unknown
// types or counts larger than the file can hold.
File read(const std::filesystem::path& path);
// Writes atomically. Scalar property vectors must have `count` values.
void write(const File& file, const std::filesystem::path& path);

}  // namespace treelobes::ply
