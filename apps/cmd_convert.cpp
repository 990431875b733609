// `treelobes convert INPUT --out OUTPUT [--bounds BOX] [--to-metres]`: any readable point cloud to
// LAS, PLY, PCD or XYZ/CSV text (what `pdal translate` does for our users). LAS or LAZ to LAS
// without --bounds or --to-metres copies the point records verbatim (LAZ gives its uncompressed
// twin, record for record, with the same header fields, VLRs and EVLRs); every other conversion
// goes through the point cloud and keeps its attributes, scale/offset and CRS as the writers do.
// --to-metres gives a survey in feet its coordinates and CRS in metres (core/crs_metres.hpp).
#include "apps/command.hpp"
#include "apps/option_table.hpp"
#include "core/cloud_io.hpp"
#include "core/crs_metres.hpp"
#include "core/error.hpp"
#include "core/las_io.hpp"
#include "core/log.hpp"
#include "core/version.hpp"

#include <nlohmann/json.hpp>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>

namespace treelobes::cli {

namespace {

struct ConvertOptions {
    std::string input;
    std::string out;
    std::string bounds;
    bool to_metres = false;
};

bool starts_with_lasf(const std::filesystem::path& path) {
    std::ifstream in(path, std::ios::binary);
    char magic[4] = {};
    in.read(magic, 4);
    return in.gcount() == 4 && std::string(magic, 4) == "LASF";
}

struct ConvertResult {
    std::size_t points = 0;
    std::string method;  // "records" (verbatim point records) or "cloud"
    std::string input_format;
};

ConvertResult copy_records(const std::filesystem::path& input, const std::filesystem::path& output) {
    const LasRecords records = read_las_records(input);
    write_las_records(records, output);
    return {static_cast<std::size_t>(records.point_count), "records",
            std::string(records.compressed ? "LAZ" : "LAS") + " 1." + std::to_string(records.minor) + ", point format " +
                    std::to_string(records.point_format)};
}

// Says what --to-metres multiplied, the vertical factor's source with it (a 2D CRS in feet names no
// unit for z; US State Plane surveys give z in the unit of x and y).
void report_metres(const std::string& input, const MetricCrs& metric) {
    char text[512];
    std::snprintf(text, sizeof text, "%s: x and y in %s multiplied by %.10g, z in %s (%s) by %.10g, to metres", input.c_str(),
                  metric.horizontal_unit.c_str(), metric.horizontal, metric.vertical_unit.c_str(), metric.vertical_source.c_str(),
                  metric.vertical);
    log_info(text);
}

ConvertResult convert_cloud(const std::filesystem::path& input, const std::filesystem::path& output, const std::optional<Box3d>& bounds,
                            bool to_metres) {
    CloudReadOptions options;
    options.bounds = bounds;
    PointCloud cloud = read_point_cloud(input, options);
    if (to_metres) {
        const MetricCrs metric = crs_in_metres(cloud.georef, input.string());
        report_metres(input.string(), metric);
        convert_to_metres(cloud, metric);
    }
    write_point_cloud(cloud, output);
    std::string format = cloud.source.laz ? "LAZ" : cloud.source.format;
    if (!cloud.source.version.empty()) format += " " + cloud.source.version;
    return {cloud.size(), "cloud", format};
}

int run_convert(const ConvertOptions& options, const OptionTable& table, const GlobalOptions& global) {
    const std::filesystem::path input(options.input), output(options.out);
    std::error_code ec;
    if (std::filesystem::exists(output, ec) && std::filesystem::equivalent(input, output, ec))
        throw Error::usage("--out " + options.out + " is the input file; choose another output");
    const std::string out_ext = file_extension(output);
    if (out_ext == "laz") throw Error::usage("--out " + options.out + ": writing LAZ is not supported; write .las");
    std::optional<Box3d> bounds;
    if (!options.bounds.empty()) bounds = parse_bounds(options.bounds);

    const std::string in_ext = file_extension(input);
    const bool las_input = in_ext == "las" || in_ext == "laz" || (std::filesystem::is_regular_file(input, ec) && starts_with_lasf(input));
    const ConvertResult result = las_input && out_ext == "las" && !bounds && !options.to_metres
                                         ? copy_records(input, output)
                                         : convert_cloud(input, output, bounds, options.to_metres);
    if (global.json) {
        std::cout << nlohmann::json{{"treelobes", kVersion},   {"input", options.input},
                                    {"options", table.json()}, {"input_format", result.input_format},
                                    {"output", options.out},   {"points", result.points},
                                    {"method", result.method}}
                             .dump(2)
                  << "\n";
    } else {
        std::cout << options.input << " (" << result.input_format << ") -> " << options.out << ": " << result.points << " points"
                  << (result.method == "records" ? ", point records copied verbatim" : "") << "\n";
    }
    return 0;
}

}  // namespace

void add_convert_command(CLI::App& app, const GlobalOptions& global, Job& job) {
    auto options = std::make_shared<ConvertOptions>();
    CLI::App* sub = app.add_subcommand("convert",
                                       "Convert a point cloud (LAS, LAZ, COPC, PLY, PCD, XYZ/CSV) to LAS, PLY, PCD or XYZ/CSV; LAZ to LAS "
                                       "gives the uncompressed file record for record");
    auto table = std::make_shared<OptionTable>(sub);
    sub->add_option("input", options->input, "Point cloud to read")->required();
    table->add("--out", options->out, "Output file; its extension picks the format (.las .ply .pcd .xyz .txt .csv)")->required();
    table->add("--bounds", options->bounds,
               "Keep only the points inside minx,miny,minz,maxx,maxy,maxz (or minx,miny,maxx,maxy); COPC files "
               "read only the octree nodes that meet the box");
    table->add_flag("--to-metres", options->to_metres,
                    "Give a survey in feet (or another length unit) its coordinates and CRS in metres, as treelobes measures: x "
                    "and y by the CRS's unit, z by its vertical part's, else by x's; the same projection, so exact (docs/laz.md)");
    sub->callback([options, table, &global, &job] { job = [options, table, &global] { return run_convert(*options, *table, global); }; });
}

}  // namespace treelobes::cli
