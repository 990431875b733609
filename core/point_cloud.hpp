// PointCloud: float positions in a local frame plus a double-precision origin, and
// optional per-point attributes. Georeferenced coordinates (UTM: x ~ 6e5, y ~ 6e6)
// lose millimetres in float, so readers subtract an origin and writers add it back.
#pragma once

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace treelobes {

// How an extra attribute is stored on disk. Values are held as double in memory.
enum class AttributeType : std::uint8_t { UInt8, Int8, UInt16, Int16, UInt32, Int32, UInt64, Int64, Float32, Float64 };

const char* attribute_type_name(AttributeType type);
std::size_t attribute_type_size(AttributeType type);

// A named per-point attribute such as LAS Extra Bytes `treeID` or PLY `scalar_geodesic`.
struct ExtraAttribute {
    std::string name;
    AttributeType type = AttributeType::Float64;
    std::string description;        // LAS extra-bytes description (< 32 bytes)
    std::optional<double> no_data;  // LAS extra-bytes no-data value, if declared
    std::vector<double> values;     // one per point
};

// One LAS variable-length record kept verbatim so it can be written back unchanged
// (CRS records: GeoKeyDirectory 34735, GeoDoubleParams 34736, GeoAsciiParams 34737,
// OGC WKT 2112).
struct RawVlr {
    std::string user_id;
    std::uint16_t record_id = 0;
    std::string description;
    std::vector<std::uint8_t> data;
};

// Coordinate reference system as found in the input.
struct Georeference {
    std::string crs_wkt;           // empty when unknown
    std::vector<RawVlr> las_vlrs;  // CRS VLRs to pass through on LAS write
    // EPSG codes of the linear units the GeoTIFF keys declare (ProjLinearUnitsGeoKey 3076,
    // VerticalUnitsGeoKey 4099: 9001 metre, 9002 foot, 9003 US survey foot); 0 when not declared.
    int linear_unit_code = 0;
    int vertical_unit_code = 0;
    bool empty() const { return crs_wkt.empty() && las_vlrs.empty(); }
};

// What a reader learned about the file it read (for `treelobes info` and for writers
// that want to keep the input's format choices).
struct SourceFormat {
    std::string format;         // "las", "ply", "pcd", "xyz", ...
    std::string version;        // "1.2" for LAS, "ascii"/"binary_little_endian" for PLY
    int las_point_format = -1;  // 0..10 for LAS input
    Eigen::Vector3d las_scale{0.001, 0.001, 0.001};
    Eigen::Vector3d las_offset{0, 0, 0};
    std::size_t dropped_non_finite = 0;  // points dropped because a coordinate was NaN/inf
    // LAZ input (format stays "las": the points are LAS records once decoded).
    bool laz = false;
    std::uint32_t laz_chunk_size = 0;  // points per chunk; 0xFFFFFFFF = variable-size chunks
    std::size_t laz_chunks = 0;
    // COPC input: octree depth (levels) and nodes holding points; -1 when not COPC.
    int copc_levels = -1;
    std::size_t copc_nodes = 0;
    std::size_t copc_nodes_read = 0;  // nodes decoded (fewer than copc_nodes under a bounds query)
};

// ASPRS classification codes (LAS 1.4 R15, Table 17) that the pipeline reads or writes.
inline constexpr std::uint8_t kAsprsGround = 2, kAsprsLowNoise = 7, kAsprsHighNoise = 18;

struct PointCloud {
    Eigen::Vector3d origin{0, 0, 0};         // add to a local position for the original coordinates
    std::vector<Eigen::Vector3f> positions;  // local coordinates (metres)

    // Optional standard attributes: empty vector = absent, otherwise one value per point.
    std::vector<std::uint16_t> intensity;
    std::vector<std::uint8_t> return_number;
    std::vector<std::uint8_t> number_of_returns;
    std::vector<std::uint8_t> classification;  // ASPRS codes (kAsprsGround, ...)
    std::vector<std::array<std::uint16_t, 3>> rgb;
    std::vector<double> gps_time;
    std::vector<ExtraAttribute> extras;

    Georeference georef;
    SourceFormat source;

    std::size_t size() const { return positions.size(); }
    bool empty() const { return positions.empty(); }

    Eigen::Vector3d global(std::size_t i) const { return origin + positions[i].cast<double>(); }

    // Extra attribute lookup by name; nullptr when absent.
    const ExtraAttribute* extra(const std::string& name) const;
    ExtraAttribute* extra(const std::string& name);
    // Returns the attribute, creating it (filled with `fill`) when absent.
    ExtraAttribute& add_extra(const std::string& name, AttributeType type, double fill = 0.0);

    // Names of the attributes present ("intensity", "classification", "treeID", ...).
    std::vector<std::string> attribute_names() const;

    // Keeps the points whose flag is true, in order, with all their attributes.
    PointCloud subset(const std::vector<bool>& keep) const;
    PointCloud subset(const std::vector<std::size_t>& indices) const;

    // Bounding box in local coordinates; throws on an empty cloud.
    std::pair<Eigen::Vector3f, Eigen::Vector3f> bounds() const;

    // Throws Error(InvalidInput) when an attribute vector's length differs from size().
    void check_consistent(const std::string& context) const;
};

}  // namespace treelobes
