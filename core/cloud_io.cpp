#include "core/cloud_io.hpp"

#include "core/error.hpp"

#include <algorithm>
#include <fstream>

namespace fs = std::filesystem;

namespace treelobes {

std::string file_extension(const fs::path& path) {
    std::string ext = path.extension().string();
    if (!ext.empty() && ext.front() == '.') ext.erase(ext.begin());
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return ext;
}

namespace {

bool is_text_extension(const std::string& ext) { return ext == "xyz" || ext == "txt" || ext == "csv" || ext == "pts" || ext == "asc"; }

// Identifies files by their first bytes when the extension is unknown.
std::string sniff_format(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    char head[8] = {};
    in.read(head, sizeof head);
    const std::string magic(head, static_cast<std::size_t>(in.gcount()));
    if (magic.starts_with("LASF")) return "las";
    if (magic.starts_with("ply")) return "ply";
    if (magic.starts_with("# .PCD") || magic.starts_with("VERSION")) return "pcd";
    return "";
}

void check_readable(const fs::path& path) {
    std::error_code ec;
    if (!fs::exists(path, ec)) throw Error::input(path.string(), "no such file");
    if (fs::is_directory(path, ec)) throw Error::input(path.string(), "is a directory, expected a point-cloud file");
}

// Formats without a spatial index are read whole, then cut to the box.
PointCloud keep_inside(PointCloud cloud, const Box3d& box) {
    std::vector<bool> keep(cloud.size());
    for (std::size_t i = 0; i < cloud.size(); ++i) keep[i] = box.contains(cloud.global(i));
    return cloud.subset(keep);
}

PointCloud read_other_format(const fs::path& path, const std::string& ext) {
    if (ext == "ply") return read_ply_cloud(path);
    if (ext == "pcd") return read_pcd(path);
    return read_text_cloud(path);
}

}  // namespace

PointCloud read_point_cloud(const fs::path& path, const CloudReadOptions& options) {
    check_readable(path);
    std::string ext = file_extension(path);
    if (ext != "las" && ext != "laz" && ext != "ply" && ext != "pcd" && !is_text_extension(ext)) {
        ext = sniff_format(path);
        if (ext.empty())
            throw Error::input(path.string(), "unknown point-cloud format (expected .las, .laz, .ply, .pcd, .xyz, .txt, .csv, .pts)");
    }
    // LAZ is LAS with compressed point data: one reader for both.
    if (ext == "las" || ext == "laz") return read_las(path, options);
    PointCloud cloud = read_other_format(path, ext);
    return options.bounds ? keep_inside(std::move(cloud), *options.bounds) : cloud;
}

void write_point_cloud(const PointCloud& cloud, const fs::path& path) {
    const std::string ext = file_extension(path);
    if (ext == "las") return write_las(cloud, path);
    if (ext == "ply") return write_ply_cloud(cloud, path);
    if (ext == "pcd") return write_pcd(cloud, path);
    if (is_text_extension(ext)) return write_text_cloud(cloud, path);
    if (ext == "laz") throw Error::usage(path.string() + ": writing LAZ is not supported; write .las");
    throw Error::usage(path.string() + ": unknown output format '." + ext + "' (expected .las, .ply, .pcd, .xyz, .txt, .csv)");
}

}  // namespace treelobes
