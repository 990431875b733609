// Loader of config/species.yaml. yaml-cpp stays in this file. Every map is read through a
// StrictMap that remembers which keys were consumed, so a typo ("donw_angle") is reported as an
// unknown key instead of silently falling back to a default.
#include "config/species_library.hpp"
#include "config/species_profile.hpp"

#include "core/error.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <map>
#include <set>
#include <sstream>

namespace treelobes {

namespace {

constexpr int kMaxLevels = 4;  // trunk + 3 branch orders (Weber & Penn use at most 4)

std::string format_number(double value) {
    std::ostringstream out;
    out << value;
    return out.str();
}

// Where a value sits: file, species and dotted key path, plus the YAML line when known.
struct Where {
    std::string file;
    std::string species;  // empty above the species list
    std::string key;

    Where child(const std::string& name) const { return {file, species, key.empty() ? name : key + "." + name}; }
    Where element(std::size_t index) const { return {file, species, key + "[" + std::to_string(index) + "]"}; }

    [[noreturn]] void fail(const YAML::Node& node, const std::string& what) const {
        std::string message = file;
        if (node.IsDefined() && node.Mark().line >= 0) message += ":" + std::to_string(node.Mark().line + 1);
        message += ": ";
        if (!species.empty()) message += "species '" + species + "': ";
        if (!key.empty()) message += "key '" + key + "': ";
        throw Error::usage(message + what);
    }
};

double read_double(const YAML::Node& node, const Where& where, double min, double max) {
    if (!node.IsScalar()) where.fail(node, "expected a number");
    double value = 0;
    try {
        value = node.as<double>();
    } catch (const YAML::Exception&) {
        where.fail(node, "expected a number, got '" + node.Scalar() + "'");
    }
    if (!std::isfinite(value) || value < min || value > max)
        where.fail(node, format_number(value) + " is outside [" + format_number(min) + ", " + format_number(max) + "]");
    return value;
}

int read_int(const YAML::Node& node, const Where& where, int min, int max) {
    if (!node.IsScalar()) where.fail(node, "expected an integer");
    long long value = 0;
    try {
        value = node.as<long long>();
    } catch (const YAML::Exception&) {
        where.fail(node, "expected an integer, got '" + node.Scalar() + "'");
    }
    if (value < min || value > max)
        where.fail(node, std::to_string(value) + " is outside [" + std::to_string(min) + ", " + std::to_string(max) + "]");
    return static_cast<int>(value);
}

std::string read_string(const YAML::Node& node, const Where& where) {
    if (!node.IsScalar()) where.fail(node, "expected a string");
    return node.Scalar();
}

// A YAML map whose keys must all be consumed. finish() reports the first unknown key.
class StrictMap {
public:
    StrictMap(const YAML::Node& node, Where where) : node_(node), where_(std::move(where)) {
        if (!node_.IsMap()) where_.fail(node_, "expected a map of keys");
        std::set<std::string> seen;
        for (const auto& item : node_) {
            const std::string key = item.first.Scalar();
            if (!seen.insert(key).second) where_.child(key).fail(item.first, "duplicate key");
        }
    }

    // Every key asked for is a known key, present or not (listed when an unknown one shows up).
    bool has(const std::string& key) const {
        known_.insert(key);
        return static_cast<bool>(node_[key]);
    }

    YAML::Node get(const std::string& key) {
        known_.insert(key);
        const YAML::Node value = node_[key];
        if (!value) where_.child(key).fail(node_, "missing required key");
        used_.insert(key);
        return value;
    }

    Where where(const std::string& key) const { return where_.child(key); }

    double number(const std::string& key, double min, double max) { return read_double(get(key), where(key), min, max); }
    void number(const std::string& key, double& out, double min, double max, bool required = false) {
        if (required || has(key)) out = number(key, min, max);
    }
    int integer(const std::string& key, int min, int max) { return read_int(get(key), where(key), min, max); }
    void integer(const std::string& key, int& out, int min, int max, bool required = false) {
        if (required || has(key)) out = integer(key, min, max);
    }
    std::string string(const std::string& key) { return read_string(get(key), where(key)); }

    StrictMap map(const std::string& key) { return StrictMap(get(key), where(key)); }

    // Rejects keys nobody asked for, naming the allowed ones.
    void finish() const {
        for (const auto& item : node_) {
            const std::string key = item.first.Scalar();
            if (used_.count(key)) continue;
            std::string known;
            for (const auto& k : known_) known += (known.empty() ? "" : ", ") + k;
            where_.child(key).fail(item.first, "unknown key (known here: " + known + ")");
        }
    }

private:
    YAML::Node node_;
    Where where_;
    std::set<std::string> used_;
    mutable std::set<std::string> known_;
};

ValueRange read_range(StrictMap& map, const std::string& key, double min, double max) {
    const YAML::Node node = map.get(key);
    const Where where = map.where(key);
    if (!node.IsSequence() || node.size() != 2) where.fail(node, "expected [min, max]");
    ValueRange range{read_double(node[0], where.element(0), min, max), read_double(node[1], where.element(1), min, max)};
    if (range.min > range.max) where.fail(node, "min " + format_number(range.min) + " is greater than max " + format_number(range.max));
    return range;
}

std::array<int, 2> read_ratio(StrictMap& map, const std::string& key) {
    const YAML::Node node = map.get(key);
    const Where where = map.where(key);
    if (!node.IsSequence() || node.size() != 2) where.fail(node, "expected [a, b] (the 'a : b' of Livny et al. 2011, Appendix A)");
    return {read_int(node[0], where.element(0), 1, 16), read_int(node[1], where.element(1), 1, 16)};
}

template <typename Enum, std::size_t N>
Enum read_enum(StrictMap& map, const std::string& key, const std::array<Enum, N>& values, const char* (*name)(Enum)) {
    const YAML::Node node = map.get(key);
    const std::string text = read_string(node, map.where(key));
    std::string allowed;
    for (Enum v : values) {
        if (text == name(v)) return v;
        allowed += (allowed.empty() ? "" : ", ") + std::string(name(v));
    }
    map.where(key).fail(node, "'" + text + "' is not one of " + allowed);
}

ReconstructionParameters read_reconstruction(StrictMap map) {
    ReconstructionParameters p;
    // Table 1 spans beta 1.3-2.0, gamma 1.2-1.9, f_s 0.8-0.986; the bounds leave room for
    // tuning but reject values that make Dijkstra or Eq. (1) meaningless.
    p.beta = map.number("beta", 0.5, 4.0);
    p.gamma = map.number("gamma", 0.1, 4.0);
    p.fs = map.number("fs", 0.05, 1.0);
    map.finish();
    return p;
}

VariationProfile read_variation(StrictMap map) {
    VariationProfile v;
    v.height_m = read_range(map, "height_m", 0.5, 120.0);
    v.age_years = read_range(map, "age_years", 1.0, 2000.0);
    v.dbh_m = read_range(map, "dbh_m", 0.01, 5.0);
    map.finish();
    return v;
}

StemLevel read_level(StrictMap map, bool trunk) {
    StemLevel l;
    if (!trunk) {
        map.number("branches", l.branches, 0, 200, true);
        map.number("down_angle", l.down_angle, -180, 180, true);
        map.number("down_angle_v", l.down_angle_v, -180, 180);
        map.number("rotate", l.rotate, -360, 360, true);
        map.number("rotate_v", l.rotate_v, 0, 360);
        map.integer("whorl", l.whorl, 1, 12);
        map.number("start", l.start, 0, 0.95);
    }
    map.number("length", l.length, 0.01, trunk ? 1.0 : 3.0, true);
    map.number("length_v", l.length_v, 0, 1.0);
    map.number("taper", l.taper, 0, 1.0, true);
    map.number("taper_power", l.taper_power, 0.2, 3.0);
    map.integer("segments", l.segments, 1, 40, true);
    map.number("curve", l.curve, -360, 360);
    map.number("curve_back", l.curve_back, -360, 360);
    map.number("curve_v", l.curve_v, -360, 360);
    map.number("seg_splits", l.seg_splits, 0, 2.0);
    map.number("split_angle", l.split_angle, 0, 180);
    map.number("split_angle_v", l.split_angle_v, 0, 180);
    map.number("tropism", l.tropism, -10, 10);
    map.finish();
    return l;
}

LeafProfile read_leaves(StrictMap map) {
    LeafProfile f;
    f.shape = read_enum(map, "shape", std::array{LeafShape::Broad, LeafShape::Needle, LeafShape::Leaflet}, leaf_shape_name);
    map.number("per_branch", f.per_branch, 0, 2000, true);
    map.integer("cluster", f.cluster, 1, 40);
    map.number("length_m", f.length_m, 0.005, 3.0, true);
    map.number("width_m", f.width_m, 0.0005, 1.5, true);
    map.number("size_v", f.size_v, 0, 0.9);
    map.number("down_angle", f.down_angle, 0, 180);
    map.number("down_angle_v", f.down_angle_v, 0, 90);
    map.number("face_up", f.face_up, 0, 1);
    map.number("start", f.start, 0, 1);
    map.integer("levels", f.levels, 1, kMaxLevels - 1);
    map.number("lai", f.lai, 0, 12);
    map.finish();
    return f;
}

GrowthProfile read_growth(StrictMap map) {
    GrowthProfile g;
    g.shape = read_enum(map, "shape",
                        std::array{CrownShape::Conical, CrownShape::Spherical, CrownShape::Hemispherical, CrownShape::Cylindrical,
                                   CrownShape::TaperedCylindrical, CrownShape::Flame, CrownShape::InverseConical, CrownShape::TendFlame},
                        crown_shape_name);
    map.number("base_size", g.base_size, 0, 0.98, true);
    map.number("base_size_v", g.base_size_v, 0, 0.5);
    map.integer("base_splits", g.base_splits, 0, 8);
    map.number("ratio_power", g.ratio_power, 0, 4);
    map.number("flare", g.flare, 0, 3);
    map.number("lean_v", g.lean_v, 0, 45);
    map.number("dead_crown", g.dead_crown, 0, 0.9);
    map.number("bark_reflectance", g.bark_reflectance, 0.01, 1);
    map.number("leaf_reflectance", g.leaf_reflectance, 0.01, 1);

    const YAML::Node levels = map.get("levels");
    const Where where = map.where("levels");
    if (!levels.IsSequence() || levels.size() < 2 || levels.size() > kMaxLevels)
        where.fail(levels, "expected a list of 2-" + std::to_string(kMaxLevels) + " stem levels (trunk first)");
    for (std::size_t i = 0; i < levels.size(); ++i) g.levels.push_back(read_level(StrictMap(levels[i], where.element(i)), i == 0));
    g.leaves = read_leaves(map.map("leaves"));
    map.finish();
    return g;
}

PatchProfile read_patch(StrictMap map) {
    PatchProfile p;
    StrictMap branch = map.map("branch");
    p.chain_pts = branch.integer("chain_pts", 2, 100);
    p.phototropism = branch.number("phototropism", -1, 1);
    p.gravitropism = branch.number("gravitropism", -1, 1);
    p.allometric = branch.number("allometric", 0.1, 4);
    branch.finish();

    StrictMap leaf = map.map("leaf");
    p.leaf_phototropism = leaf.number("phototropism", -1, 1);
    p.leaf_gravitropism = leaf.number("gravitropism", -1, 1);
    p.face_up = leaf.number("face_up", 0, 1);
    leaf.finish();

    StrictMap branching = map.map("branching");
    p.branch_distr = read_ratio(branching, "branch_distr");
    p.num_twigs = branching.integer("num_twigs", 0, 10);
    p.branching_angle = branching.number("branching_angle", 0, 180);
    p.spiral_angle = branching.number("spiral_angle", 0, 360);
    p.init_thickness = branching.number("init_thickness", 0.01, 10);
    branching.finish();

    StrictMap leaf_control = map.map("leaf_control");
    p.leaf_distr = read_ratio(leaf_control, "leaf_distr");
    p.num_leaves = leaf_control.integer("num_leaves", 0, 40);
    p.leaf_angle = leaf_control.number("leaf_angle", 0, 180);
    p.leaf_spiral_angle = leaf_control.number("spiral_angle", 0, 360);
    p.orient_up = leaf_control.number("orient_up", 0, 1);
    leaf_control.finish();
    map.finish();
    return p;
}

bool valid_name(const std::string& name) {
    if (name.empty() || !std::islower(static_cast<unsigned char>(name[0]))) return false;
    return std::all_of(name.begin(), name.end(), [](char c) {
        return std::islower(static_cast<unsigned char>(c)) || std::isdigit(static_cast<unsigned char>(c)) || c == '_';
    });
}

SpeciesProfile read_species(const YAML::Node& node, const Where& list_where, const ReconstructionParameters& defaults) {
    StrictMap map(node, list_where);
    SpeciesProfile s;
    s.entry.name = map.string("name");
    if (!valid_name(s.entry.name))
        map.where("name").fail(node["name"], "'" + s.entry.name + "' must be lower-case letters, digits and '_'");
    // From here on every message names the species.
    StrictMap named(node, Where{list_where.file, s.entry.name, ""});
    named.get("name");
    s.entry.display_name = named.string("display_name");
    s.entry.id = named.integer("id", 1, 255);
    if (named.has("description")) s.description = named.string("description");
    s.reconstruction_from_table1 = named.has("reconstruction");
    s.entry.reconstruction = s.reconstruction_from_table1 ? read_reconstruction(named.map("reconstruction")) : defaults;
    s.variation = read_variation(named.map("variation"));
    s.growth = read_growth(named.map("growth"));
    s.patch = read_patch(named.map("patch"));
    named.finish();
    return s;
}

YAML::Node parse_yaml(const std::filesystem::path& file) {
    if (!std::filesystem::is_regular_file(file)) throw Error::input(file.string(), "species file not found");
    try {
        return YAML::LoadFile(file.string());
    } catch (const YAML::ParserException& e) {
        throw Error::input(file.string(),
                           "line " + std::to_string(e.mark.line + 1) + ", column " + std::to_string(e.mark.column + 1) + ": " + e.msg);
    } catch (const YAML::Exception& e) {
        throw Error::input(file.string(), e.what());
    }
}

std::string normalise_name(const std::string& name) {
    std::string out;
    for (char c : name) out += (c == ' ' || c == '-') ? '_' : static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return out;
}

}  // namespace

const char* crown_shape_name(CrownShape shape) {
    switch (shape) {
        case CrownShape::Conical:
            return "conical";
        case CrownShape::Spherical:
            return "spherical";
        case CrownShape::Hemispherical:
            return "hemispherical";
        case CrownShape::Cylindrical:
            return "cylindrical";
        case CrownShape::TaperedCylindrical:
            return "tapered_cylindrical";
        case CrownShape::Flame:
            return "flame";
        case CrownShape::InverseConical:
            return "inverse_conical";
        case CrownShape::TendFlame:
            return "tend_flame";
    }
    return "?";
}

double crown_shape_ratio(CrownShape shape, double r) {
    constexpr double pi = 3.14159265358979323846;
    r = std::clamp(r, 0.0, 1.0);
    switch (shape) {
        case CrownShape::Conical:
            return 0.2 + 0.8 * r;
        case CrownShape::Spherical:
            return 0.2 + 0.8 * std::sin(pi * r);
        case CrownShape::Hemispherical:
            return 0.2 + 0.8 * std::sin(0.5 * pi * r);
        case CrownShape::Cylindrical:
            return 1.0;
        case CrownShape::TaperedCylindrical:
            return 0.5 + 0.5 * r;
        case CrownShape::Flame:
            return r <= 0.7 ? r / 0.7 : (1.0 - r) / 0.3;
        case CrownShape::InverseConical:
            return 1.0 - 0.8 * r;
        case CrownShape::TendFlame:
            return r <= 0.7 ? 0.5 + 0.5 * r / 0.7 : 0.5 + 0.5 * (1.0 - r) / 0.3;
    }
    return 1.0;
}

const char* leaf_shape_name(LeafShape shape) {
    switch (shape) {
        case LeafShape::Broad:
            return "broad";
        case LeafShape::Needle:
            return "needle";
        case LeafShape::Leaflet:
            return "leaflet";
    }
    return "?";
}

std::filesystem::path default_species_file() {
    const char* env = std::getenv("TREELOBES_SPECIES");
    if (env && *env) return env;
    return TREELOBES_SPECIES_FILE;
}

std::vector<SpeciesProfile> load_species_profiles(const std::filesystem::path& file) {
    const YAML::Node root = parse_yaml(file);
    const Where top{file.string(), "", ""};
    StrictMap map(root, top);
    const int version = map.integer("version", 1, 1);
    (void)version;  // only version 1 exists; the range check rejects others
    StrictMap defaults_map = map.map("defaults");
    const ReconstructionParameters defaults = read_reconstruction(defaults_map.map("reconstruction"));
    defaults_map.finish();

    const YAML::Node list = map.get("species");
    if (!list.IsSequence() || list.size() == 0) map.where("species").fail(list, "expected a non-empty list of species");
    std::vector<SpeciesProfile> profiles;
    std::map<std::string, int> names;
    std::map<int, std::string> ids;
    for (std::size_t i = 0; i < list.size(); ++i) {
        SpeciesProfile s = read_species(list[i], map.where("species").element(i), defaults);
        const Where where{file.string(), s.entry.name, ""};
        if (names.count(s.entry.name)) where.child("name").fail(list[i]["name"], "species name used twice");
        if (ids.count(s.entry.id))
            where.child("id").fail(list[i]["id"], "id " + std::to_string(s.entry.id) + " already used by '" + ids[s.entry.id] + "'");
        names[s.entry.name] = s.entry.id;
        ids[s.entry.id] = s.entry.name;
        profiles.push_back(std::move(s));
    }
    map.finish();
    return profiles;
}

std::vector<SpeciesEntry> load_species_entries(const std::filesystem::path& file) {
    std::vector<SpeciesEntry> entries;
    for (const auto& profile : load_species_profiles(file)) entries.push_back(profile.entry);
    return entries;
}

namespace {

template <typename T, typename Name>
const T& find_by_name(const std::vector<T>& items, const std::string& name, Name name_of) {
    const std::string wanted = normalise_name(name);
    for (const auto& item : items)
        if (normalise_name(name_of(item)) == wanted) return item;
    std::string known;
    for (const auto& item : items) known += (known.empty() ? "" : ", ") + name_of(item);
    throw Error::usage("unknown species '" + name + "' (known: " + known + ")");
}

}  // namespace

SpeciesEntry find_species(const std::vector<SpeciesEntry>& entries, const std::string& name) {
    return find_by_name(entries, name, [](const SpeciesEntry& e) { return e.name; });
}

const SpeciesProfile& find_species_profile(const std::vector<SpeciesProfile>& profiles, const std::string& name) {
    return find_by_name(profiles, name, [](const SpeciesProfile& p) { return p.entry.name; });
}

}  // namespace treelobes
