#include "core/ply_format.hpp"

#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "core/memory_limit.hpp"

#include <bit>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <sstream>
#include <string_view>

namespace fs = std::filesystem;

namespace treelobes::ply {

// The binary writer emits native values as little-endian.
static_assert(std::endian::native == std::endian::little);

const Property* Element::find(const std::string& property) const {
    for (const auto& p : properties)
        if (p.name == property) return &p;
    return nullptr;
}

const Element* File::find(const std::string& element) const {
    for (const auto& e : elements)
        if (e.name == element) return &e;
    return nullptr;
}

namespace {

bool parse_type(const std::string& word, AttributeType& type) {
    static const std::pair<const char*, AttributeType> names[] = {
            {"char", AttributeType::Int8},      {"int8", AttributeType::Int8},       {"uchar", AttributeType::UInt8},
            {"uint8", AttributeType::UInt8},    {"short", AttributeType::Int16},     {"int16", AttributeType::Int16},
            {"ushort", AttributeType::UInt16},  {"uint16", AttributeType::UInt16},   {"int", AttributeType::Int32},
            {"int32", AttributeType::Int32},    {"uint", AttributeType::UInt32},     {"uint32", AttributeType::UInt32},
            {"float", AttributeType::Float32},  {"float32", AttributeType::Float32}, {"double", AttributeType::Float64},
            {"float64", AttributeType::Float64}};
    for (const auto& [name, t] : names)
        if (word == name) {
            type = t;
            return true;
        }
    return false;
}

const char* type_word(AttributeType type) {
    switch (type) {
        case AttributeType::Int8:
            return "char";
        case AttributeType::UInt8:
            return "uchar";
        case AttributeType::Int16:
            return "short";
        case AttributeType::UInt16:
            return "ushort";
        case AttributeType::Int32:
            return "int";
        case AttributeType::UInt32:
            return "uint";
        case AttributeType::Float32:
            return "float";
        default:
            return "double";  // PLY has no 64-bit integers: stored as double
    }
}

AttributeType storable(AttributeType type) {
    return type == AttributeType::Int64 || type == AttributeType::UInt64 ? AttributeType::Float64 : type;
}

struct Header {
    File file;
    std::size_t body_offset = 0;
};

Header parse_header(const std::string& data, const std::string& name) {
    const std::size_t end = data.find("end_header");
    if (data.compare(0, 3, "ply") != 0) throw Error::input(name, "not a PLY file (missing 'ply' magic)");
    if (end == std::string::npos || end > (1u << 20)) throw Error::input(name, "PLY header has no 'end_header' line");
    std::size_t body = data.find('\n', end);
    if (body == std::string::npos) throw Error::input(name, "PLY file ends right after the header");
    Header header;
    header.body_offset = body + 1;
    std::istringstream lines(data.substr(0, end));
    std::string line;
    std::getline(lines, line);  // "ply"
    int line_number = 1;
    while (std::getline(lines, line)) {
        ++line_number;
        if (!line.empty() && line.back() == '\r') line.pop_back();
        std::istringstream words(line);
        std::string keyword;
        words >> keyword;
        auto fail = [&](const std::string& what) {
            return Error::input(name, "PLY header line " + std::to_string(line_number) + ": " + what);
        };
        if (keyword.empty() || keyword == "obj_info") continue;
        if (keyword == "comment") {
            header.file.comments.push_back(line.size() > 8 ? line.substr(8) : "");
        } else if (keyword == "format") {
            std::string format, version;
            words >> format >> version;
            if (format != "ascii" && format != "binary_little_endian" && format != "binary_big_endian")
                throw fail("unknown format '" + format + "'");
            header.file.format = format;
        } else if (keyword == "element") {
            Element element;
            long long count = -1;
            words >> element.name >> count;
            if (!words || count < 0) throw fail("expected 'element <name> <count>'");
            element.count = static_cast<std::size_t>(count);
            header.file.elements.push_back(std::move(element));
        } else if (keyword == "property") {
            if (header.file.elements.empty()) throw fail("property before any element");
            Property property;
            std::string type;
            words >> type;
            if (type == "list") {
                std::string count_type, item_type;
                words >> count_type >> item_type >> property.name;
                property.is_list = true;
                if (!parse_type(count_type, property.count_type) || !parse_type(item_type, property.type))
                    throw fail("unknown list types '" + count_type + " " + item_type + "'");
            } else {
                words >> property.name;
                if (!parse_type(type, property.type)) throw fail("unknown property type '" + type + "'");
            }
            if (property.name.empty()) throw fail("property without a name");
            header.file.elements.back().properties.push_back(std::move(property));
        } else {
            throw fail("unexpected keyword '" + keyword + "'");
        }
    }
    return header;
}

class BinaryCursor {
public:
    BinaryCursor(const std::string& data, std::size_t offset, bool big_endian, const std::string& name)
            : data_(data), pos_(offset), swap_(big_endian != (std::endian::native == std::endian::big)), name_(name) {}

    double read(AttributeType type) {
        const std::size_t size = attribute_type_size(type);
        if (pos_ + size > data_.size()) throw Error::input(name_, "PLY body is truncated (file shorter than its header declares)");
        unsigned char bytes[8];
        std::memcpy(bytes, data_.data() + pos_, size);
        pos_ += size;
        if (swap_)
            for (std::size_t i = 0; i < size / 2; ++i) std::swap(bytes[i], bytes[size - 1 - i]);
        switch (type) {
            case AttributeType::Int8:
                return as<std::int8_t>(bytes);
            case AttributeType::UInt8:
                return as<std::uint8_t>(bytes);
            case AttributeType::Int16:
                return as<std::int16_t>(bytes);
            case AttributeType::UInt16:
                return as<std::uint16_t>(bytes);
            case AttributeType::Int32:
                return as<std::int32_t>(bytes);
            case AttributeType::UInt32:
                return as<std::uint32_t>(bytes);
            case AttributeType::Float32:
                return as<float>(bytes);
            default:
                return as<double>(bytes);
        }
    }
    std::size_t remaining() const { return data_.size() - std::min(pos_, data_.size()); }

private:
    template <typename T>
    static double as(const unsigned char* bytes) {
        T value;
        std::memcpy(&value, bytes, sizeof(T));
        return static_cast<double>(value);
    }
    const std::string& data_;
    std::size_t pos_;
    bool swap_;
    const std::string& name_;
};

class AsciiCursor {
public:
    AsciiCursor(const std::string& data, std::size_t offset, const std::string& name) : data_(data), pos_(offset), name_(name) {}

    double read(AttributeType) {
        while (pos_ < data_.size() && std::isspace(static_cast<unsigned char>(data_[pos_]))) ++pos_;
        if (pos_ >= data_.size()) throw Error::input(name_, "PLY body is truncated (fewer values than the header declares)");
        std::size_t end = pos_;
        while (end < data_.size() && !std::isspace(static_cast<unsigned char>(data_[end]))) ++end;
        double value = 0;
        const char* first = data_.data() + pos_;
        const auto [ptr, ec] = std::from_chars(first, data_.data() + end, value);
        if (ec != std::errc() || ptr != data_.data() + end) {
            const std::string token(first, data_.data() + end);
            if (token == "nan" || token == "-nan")
                value = std::nan("");
            else if (token == "inf")
                value = HUGE_VAL;
            else if (token == "-inf")
                value = -HUGE_VAL;
            else
                throw Error::input(name_, "PLY body: '" + token + "' is not a number");
        }
        pos_ = end;
        return value;
    }
    std::size_t remaining() const { return data_.size() - std::min(pos_, data_.size()); }

private:
    const std::string& data_;
    std::size_t pos_;
    const std::string& name_;
};

// Smallest number of bytes one item of the element can take: bounds the count a header may claim.
std::size_t minimum_item_size(const Element& element, bool ascii) {
    std::size_t size = 0;
    for (const auto& p : element.properties) size += ascii ? 2 : attribute_type_size(p.is_list ? p.count_type : p.type);
    return size;
}

// Bytes one item of the element takes once read: a double per scalar property, a vector per
// list (its values come on top, bounded by the file size).
std::uint64_t held_item_size(const Element& element) {
    std::uint64_t size = 0;
    for (const auto& p : element.properties) size += p.is_list ? sizeof(std::vector<double>) : sizeof(double);
    return size;
}

template <typename Cursor>
void read_body(Cursor& cursor, File& file, bool ascii, const std::string& name) {
    for (auto& element : file.elements) {
        const std::size_t item = minimum_item_size(element, ascii);
        if (item > 0 && element.count > cursor.remaining() / item + (ascii ? 1 : 0))
            throw Error::input(name, "PLY header declares " + std::to_string(element.count) + " " + element.name +
                                             " items, more than the file can hold");
        if (item == 0 && element.count > 0) throw Error::input(name, "PLY element '" + element.name + "' has no properties");
        check_memory_estimate(element.count * held_item_size(element), name,
                              "the header's " + std::to_string(element.count) + " " + element.name + " items");
        for (auto& p : element.properties) {
            if (p.is_list)
                p.lists.resize(element.count);
            else
                p.values.resize(element.count);
        }
        for (std::size_t i = 0; i < element.count; ++i) {
            for (auto& p : element.properties) {
                if (!p.is_list) {
                    p.values[i] = cursor.read(p.type);
                    continue;
                }
                const double length = cursor.read(p.count_type);
                if (!(length >= 0) || length > static_cast<double>(cursor.remaining()))
                    throw Error::input(name, "PLY list in element '" + element.name + "' has invalid length");
                auto& list = p.lists[i];
                list.resize(static_cast<std::size_t>(length));
                for (double& v : list) v = cursor.read(p.type);
            }
        }
    }
}

template <typename T>
void put(std::ostream& out, double value) {
    const T v = static_cast<T>(value);
    out.write(reinterpret_cast<const char*>(&v), sizeof(T));
}

void put_binary(std::ostream& out, AttributeType type, double value) {
    switch (type) {
        case AttributeType::Int8:
            put<std::int8_t>(out, value);
            break;
        case AttributeType::UInt8:
            put<std::uint8_t>(out, value);
            break;
        case AttributeType::Int16:
            put<std::int16_t>(out, value);
            break;
        case AttributeType::UInt16:
            put<std::uint16_t>(out, value);
            break;
        case AttributeType::Int32:
            put<std::int32_t>(out, value);
            break;
        case AttributeType::UInt32:
            put<std::uint32_t>(out, value);
            break;
        case AttributeType::Float32:
            put<float>(out, value);
            break;
        default:
            put<double>(out, value);
            break;
    }
}

void put_ascii(std::ostream& out, AttributeType type, double value) {
    char buffer[40];
    std::to_chars_result r;
    if (type == AttributeType::Float32)
        r = std::to_chars(buffer, buffer + sizeof buffer, static_cast<float>(value));
    else
        r = std::to_chars(buffer, buffer + sizeof buffer, value);
    out.write(buffer, r.ptr - buffer);
}

}  // namespace

File read(const fs::path& path) {
    const std::string data = read_file(path);
    const std::string name = path.string();
    Header header = parse_header(data, name);
    if (header.file.format == "ascii") {
        AsciiCursor cursor(data, header.body_offset, name);
        read_body(cursor, header.file, true, name);
    } else {
        BinaryCursor cursor(data, header.body_offset, header.file.format == "binary_big_endian", name);
        read_body(cursor, header.file, false, name);
    }
    return std::move(header.file);
}

void write(const File& file, const fs::path& path) {
    if (file.format == "binary_big_endian") throw Error(ExitCode::Internal, "PLY writer: big-endian output is not supported");
    const bool ascii = file.format == "ascii";
    write_atomically(path, [&](std::ostream& out) {
        out << "ply\nformat " << (ascii ? "ascii" : "binary_little_endian") << " 1.0\n";
        for (const auto& comment : file.comments) out << "comment " << comment << "\n";
        for (const auto& element : file.elements) {
            out << "element " << element.name << " " << element.count << "\n";
            for (const auto& p : element.properties) {
                out << "property ";
                if (p.is_list) out << "list " << type_word(p.count_type) << " ";
                out << type_word(storable(p.type)) << " " << p.name << "\n";
            }
        }
        out << "end_header\n";
        for (const auto& element : file.elements) {
            for (std::size_t i = 0; i < element.count; ++i) {
                bool first = true;
                for (const auto& p : element.properties) {
                    const AttributeType type = storable(p.type);
                    if (ascii && !first) out.put(' ');
                    first = false;
                    if (!p.is_list) {
                        ascii ? put_ascii(out, type, p.values[i]) : put_binary(out, type, p.values[i]);
                        continue;
                    }
                    const auto& list = p.lists[i];
                    ascii ? put_ascii(out, p.count_type, static_cast<double>(list.size()))
                          : put_binary(out, p.count_type, static_cast<double>(list.size()));
                    for (double v : list) {
                        if (ascii) out.put(' ');
                        ascii ? put_ascii(out, type, v) : put_binary(out, type, v);
                    }
                }
                if (ascii) out.put('\n');
            }
        }
    });
}

}  // namespace treelobes::ply
