#include "forestry/tile_trees.hpp"

#include "core/error.hpp"
#include "core/geojson.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>

namespace treelobes::forestry {

namespace {

using nlohmann::json;

float median(std::vector<float> values) {
    const auto mid = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
    std::nth_element(values.begin(), mid, values.end());
    return *mid;
}

std::string fixed(double value, int digits) {
    char text[64];
    std::snprintf(text, sizeof text, "%.*f", digits, value);
    return text;
}

std::string cell(const std::optional<double>& value, int digits) { return value ? fixed(*value, digits) : std::string(); }

json value_or_null(const std::optional<double>& value, int digits) {
    if (!value) return nullptr;
    const double scale = std::pow(10.0, digits);
    return std::round(*value * scale) / scale;
}

json optional_json(const std::optional<double>& value) { return value ? json(*value) : json(nullptr); }
json outline_json(const std::vector<Eigen::Vector2d>& outline) {
    json corners = json::array();
    for (const Eigen::Vector2d& corner : outline) corners.push_back({corner.x(), corner.y()});
    return corners;
}
std::optional<double> optional_from(const json& j) {
    if (j.is_null()) return std::nullopt;
    return j.get<double>();
}

DbhQuality parse_quality(const std::string& name) {
    for (DbhQuality q : {DbhQuality::Ok, DbhQuality::PartialArc, DbhQuality::NotVisible})
        if (name == dbh_quality_name(q)) return q;
    throw Error::input("tree record", "unknown DBH quality '" + name + "'");
}

double millimetres(double metres) { return std::round(metres * 1000.0) / 1000.0; }

// Whether the tree has a model, or why not.
const char* model_name(const TreeRow& row) { return row.modelled ? "ok" : "too_few_points"; }

// The values a user reads, rounded for the tables (the record keeps full precision).
json row_properties(const TreeRow& row, const Eigen::Vector3d& origin) {
    const TreeMeasures& m = row.measures;
    return {{"global_id", row.global_id},
            {"tree_id", m.id},
            {"height_m", value_or_null(m.height, 2)},
            {"dbh_m", value_or_null(m.dbh.diameter, 3)},
            {"dbh_quality", dbh_quality_name(m.dbh.quality)},
            {"stems", m.dbh.stems > 0 ? json(m.dbh.stems) : json(nullptr)},
            {"crown_base_height_m", value_or_null(m.crown.base_height, 2)},
            {"crown_diameter_m", value_or_null(m.crown.diameter, 2)},
            {"crown_area_m2", value_or_null(m.crown.projected_area, 2)},
            {"crown_volume_m3", value_or_null(m.crown.volume, 2)},
            {"woody_volume_m3", value_or_null(m.woody_volume, 4)},
            {"species", row.species.empty() ? json(nullptr) : json(row.species)},
            {"species_confidence", value_or_null(row.species_confidence, 3)},
            {"points", m.points},
            {"lobes", row.modelled ? json(row.lobes) : json(nullptr)},
            {"model", model_name(row)},
            {"not_a_tree", m.not_a_tree ? json(*m.not_a_tree) : json(nullptr)}};
}

}  // namespace

Eigen::Vector3d estimate_stem_base(std::span<const Eigen::Vector3f> points, std::span<const float> height_above_ground, float stem_reach) {
    if (points.empty() || points.size() != height_above_ground.size())
        throw Error(ExitCode::Internal, "estimate_stem_base: points and heights expected");
    const auto lowest = std::min_element(height_above_ground.begin(), height_above_ground.end());
    const auto highest = std::max_element(height_above_ground.begin(), height_above_ground.end());
    std::vector<float> xs, ys;
    if (*lowest <= stem_reach) {
        for (std::size_t i = 0; i < points.size(); ++i)
            if (height_above_ground[i] <= *lowest + 1.0f) {
                xs.push_back(points[i].x());
                ys.push_back(points[i].y());
            }
    } else {
        const auto top = static_cast<std::size_t>(highest - height_above_ground.begin());
        xs.push_back(points[top].x());
        ys.push_back(points[top].y());
    }
    const Eigen::Vector2d xy(median(xs), median(ys));
    std::optional<double> ground = ground_under(points, height_above_ground, xy);
    if (!ground) ground = ground_under(points, height_above_ground, xy, std::numeric_limits<double>::infinity());  // all points
    return {xy.x(), xy.y(), *ground};
}

std::vector<TreeInput> split_trees(const PointCloud& cloud, std::span<const std::int32_t> tree_id,
                                   std::span<const float> height_above_ground, const std::map<int, Eigen::Vector3d>& bases,
                                   bool bases_at_stems) {
    if (tree_id.size() != cloud.size() || height_above_ground.size() != cloud.size())
        throw Error(ExitCode::Internal, "split_trees: one tree id and height per point expected");
    std::map<int, std::size_t> slot;
    for (std::int32_t id : tree_id)
        if (id > 0) slot.emplace(id, 0);
    std::vector<TreeInput> trees;
    trees.reserve(slot.size());
    for (auto& [id, index] : slot) {
        index = trees.size();
        trees.emplace_back();
        trees.back().id = id;
        trees.back().points.origin = cloud.origin;
        trees.back().points.georef = cloud.georef;
    }
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        if (tree_id[i] <= 0) continue;
        TreeInput& tree = trees[slot.at(tree_id[i])];
        tree.points.positions.push_back(cloud.positions[i]);
        tree.height_above_ground.push_back(height_above_ground[i]);
    }
    for (TreeInput& tree : trees) {
        if (const auto known = bases.find(tree.id); known != bases.end()) {
            tree.base = known->second;
            tree.base_at_stem = bases_at_stems;
        } else {
            tree.base = estimate_stem_base(tree.points.positions, tree.height_above_ground);
            tree.base_at_stem = false;
        }
    }
    return trees;
}

std::string trees_csv(const std::vector<TreeRow>& rows, const Eigen::Vector3d& origin) {
    std::string csv =
            "global_id,tree_id,x,y,z,height_m,dbh_m,dbh_quality,stems,crown_base_height_m,crown_diameter_m,crown_area_m2,crown_volume_m3,"
            "woody_volume_m3,species,species_confidence,points,lobes,model,not_a_tree\n";
    for (const TreeRow& row : rows) {
        const TreeMeasures& m = row.measures;
        const Eigen::Vector3d p = origin + m.position;
        csv += row.global_id + "," + std::to_string(m.id) + "," + fixed(p.x(), 3) + "," + fixed(p.y(), 3) + "," + fixed(p.z(), 3) + "," +
               fixed(m.height, 2) + "," + cell(m.dbh.diameter, 3) + "," + dbh_quality_name(m.dbh.quality) + "," +
               (m.dbh.stems > 0 ? std::to_string(m.dbh.stems) : std::string()) + "," + cell(m.crown.base_height, 2) + "," +
               cell(m.crown.diameter, 2) + "," + cell(m.crown.projected_area, 2) + "," + cell(m.crown.volume, 2) + "," +
               cell(m.woody_volume, 4) + "," + row.species + "," + cell(row.species_confidence, 3) + "," + std::to_string(m.points) + "," +
               (row.modelled ? std::to_string(row.lobes) : std::string()) + "," + model_name(row) + "," +
               (m.not_a_tree ? (*m.not_a_tree ? "true" : "false") : "") + "\n";
    }
    return csv;
}

std::string trees_geojson(const std::vector<TreeRow>& rows, const Eigen::Vector3d& origin, const std::string& crs_wkt) {
    json features = json::array();
    for (const TreeRow& row : rows) {
        const Eigen::Vector3d p = origin + row.measures.position;
        features.push_back(
                {{"type", "Feature"},
                 {"geometry", {{"type", "Point"}, {"coordinates", {millimetres(p.x()), millimetres(p.y()), millimetres(p.z())}}}},
                 {"properties", row_properties(row, origin)}});
    }
    return feature_collection(std::move(features), crs_wkt);
}

std::string crowns_geojson(const std::vector<TreeRow>& rows, const Eigen::Vector3d& origin, const std::string& crs_wkt) {
    json features = json::array();
    for (const TreeRow& row : rows) {
        const std::vector<Eigen::Vector2d>& outline = row.measures.crown.outline;
        json geometry = nullptr;  // a tree without a projected area: an unlocated feature (RFC 7946, 3.2)
        if (!outline.empty()) {
            json ring = json::array();
            for (std::size_t i = 0; i <= outline.size(); ++i) {  // closed: the first corner again at the end
                const Eigen::Vector2d& corner = outline[i % outline.size()];
                ring.push_back({millimetres(origin.x() + corner.x()), millimetres(origin.y() + corner.y())});
            }
            geometry = {{"type", "Polygon"}, {"coordinates", json::array({ring})}};
        }
        features.push_back({{"type", "Feature"}, {"geometry", geometry}, {"properties", row_properties(row, origin)}});
    }
    return feature_collection(std::move(features), crs_wkt);
}

std::string tree_record(const TreeRow& row, const Eigen::Vector3d& origin, const std::string& options_key) {
    const TreeMeasures& m = row.measures;
    json record = row_properties(row, origin);
    const Eigen::Vector3d p = origin + m.position;
    record["position"] = {p.x(), p.y(), p.z()};
    record["exact"] = {{"position_local", {m.position.x(), m.position.y(), m.position.z()}},
                       {"height", m.height},
                       {"dbh",
                        {{"quality", dbh_quality_name(m.dbh.quality)},
                         {"diameter", optional_json(m.dbh.diameter)},
                         {"stems", m.dbh.stems},
                         {"centre", {m.dbh.centre.x(), m.dbh.centre.y()}},
                         {"coverage", m.dbh.coverage},
                         {"rms", m.dbh.rms},
                         {"slice_points", m.dbh.slice_points},
                         {"reason", m.dbh.reason}}},
                       {"crown",
                        {{"base_height", optional_json(m.crown.base_height)},
                         {"diameter", optional_json(m.crown.diameter)},
                         {"projected_area", optional_json(m.crown.projected_area)},
                         {"outline", outline_json(m.crown.outline)},
                         {"volume", optional_json(m.crown.volume)},
                         {"volume_failure", m.crown.volume_failure}}},
                       {"woody_volume", optional_json(m.woody_volume)},
                       {"species_probabilities", m.species_probabilities}};
    record["options_key"] = options_key;
    return record.dump(1) + "\n";
}

std::optional<TreeRow> read_tree_record(const std::string& text, const std::string& options_key) {
    const json record = json::parse(text, nullptr, false);
    if (record.is_discarded() || !record.is_object() || record.value("options_key", std::string()) != options_key) return std::nullopt;
    try {
        const json& e = record.at("exact");
        TreeRow row;
        TreeMeasures& m = row.measures;
        m.id = record.at("tree_id").get<int>();
        m.points = record.at("points").get<std::size_t>();
        row.modelled = record.at("model").get<std::string>() == "ok";
        if (row.modelled) row.lobes = record.at("lobes").get<std::size_t>();
        const auto position = e.at("position_local").get<std::vector<double>>();
        m.position = {position.at(0), position.at(1), position.at(2)};
        m.height = e.at("height").get<double>();
        const json& dbh = e.at("dbh");
        m.dbh.quality = parse_quality(dbh.at("quality").get<std::string>());
        m.dbh.diameter = optional_from(dbh.at("diameter"));
        m.dbh.stems = dbh.at("stems").get<int>();
        const auto centre = dbh.at("centre").get<std::vector<double>>();
        m.dbh.centre = {centre.at(0), centre.at(1)};
        m.dbh.coverage = dbh.at("coverage").get<double>();
        m.dbh.rms = dbh.at("rms").get<double>();
        m.dbh.slice_points = dbh.at("slice_points").get<std::size_t>();
        m.dbh.reason = dbh.at("reason").get<std::string>();
        const json& crown = e.at("crown");
        m.crown.base_height = optional_from(crown.at("base_height"));
        m.crown.diameter = optional_from(crown.at("diameter"));
        m.crown.projected_area = optional_from(crown.at("projected_area"));
        for (const auto& corner : crown.at("outline").get<std::vector<std::array<double, 2>>>())
            m.crown.outline.emplace_back(corner[0], corner[1]);
        m.crown.volume = optional_from(crown.at("volume"));
        m.crown.volume_failure = crown.at("volume_failure").get<std::string>();
        m.woody_volume = optional_from(e.at("woody_volume"));
        m.species_probabilities = e.at("species_probabilities").get<std::vector<double>>();
        if (const json& flag = record.at("not_a_tree"); !flag.is_null()) m.not_a_tree = flag.get<bool>();
        return row;
    } catch (const json::exception&) {
        return std::nullopt;  // an older or damaged record: the tree is made again
    } catch (const Error&) {
        return std::nullopt;
    }
}

}  // namespace treelobes::forestry
