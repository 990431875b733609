// Writes the seed corpora of the fuzz targets (fuzz/seeds/<target>/) from the committed samples
// in data/synthetic, config/ and lsystem/examples, through the project's own writers, so the
// seeds are files the readers accept and every part of each format is present (PCD also through
// PCL's writer, for its ascii and binary_compressed encodings, which ours does not write). The real LAS
// seeds (small idtrees/lidR tiles of ../shared/data) are added by scripts/fuzz.sh when present.
//
// Usage: fuzz_make_seeds SOURCE_DIR OUT_DIR
#include "classify/jointboost.hpp"
#include "core/cloud_io.hpp"
#include "core/mesh_io.hpp"
#include "core/qsm_io.hpp"
#include "core/skeleton_io.hpp"
#include "encode/forest_file.hpp"
#include "encode/tree_file.hpp"
#include "export/cityjson.hpp"
#include "export/gltf.hpp"
#include "export/qsm.hpp"
#include "lobes/tlobe_io.hpp"

#include <pcl/io/pcd_io.h>
#include <pcl/point_types.h>
#include <zlib.h>

#include <array>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>

namespace fs = std::filesystem;
using namespace treelobes;

namespace {

void write_bytes(const fs::path& path, std::string_view bytes) {
    fs::create_directories(path.parent_path());
    std::ofstream(path, std::ios::binary).write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

std::string_view as_text(const std::vector<std::uint8_t>& bytes) { return {reinterpret_cast<const char*>(bytes.data()), bytes.size()}; }

// Every `step`-th point, attributes and extra bytes kept.
PointCloud thinned(const PointCloud& cloud, std::size_t keep) {
    std::vector<std::size_t> indices;
    for (std::size_t i = 0; i < cloud.size(); i += std::max<std::size_t>(1, cloud.size() / keep)) indices.push_back(i);
    return cloud.subset(indices);
}

// The first `count` nodes of a skeleton (parents precede children in a TreeGraph).
TreeGraph first_nodes(const TreeGraph& tree, std::size_t count) {
    TreeGraph out;
    out.origin = tree.origin;
    for (std::size_t i = 0; i < std::min(count, tree.size()); ++i)
        out.add_node(tree.nodes[i].position, tree.nodes[i].radius, tree.nodes[i].parent);
    return out;
}

// The cloud's positions and intensities in PCD's other two encodings.
void pcd_seeds_from_pcl(const PointCloud& cloud, const fs::path& out) {
    pcl::PointCloud<pcl::PointXYZI> points;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        pcl::PointXYZI p;
        p.x = cloud.positions[i].x();
        p.y = cloud.positions[i].y();
        p.z = cloud.positions[i].z();
        p.intensity = cloud.intensity.empty() ? 0.0f : static_cast<float>(cloud.intensity[i]);
        points.push_back(p);
    }
    pcl::io::savePCDFileASCII((out / "pcd/birch_ascii.pcd").string(), points);
    pcl::io::savePCDFileBinaryCompressed((out / "pcd/birch_compressed.pcd").string(), points);
}

void cloud_seeds(const fs::path& source, const fs::path& out) {
    const PointCloud birch = thinned(read_las(source / "data/synthetic/birch_3.las"), 40);
    const PointCloud tile = thinned(read_las(source / "data/synthetic/tile/tile.las"), 40);
    write_las(birch, out / "las/birch.las");
    write_las(tile, out / "las/tile.las");
    write_ply_cloud(birch, out / "ply_cloud/birch_binary.ply", true);
    write_ply_cloud(birch, out / "ply_cloud/birch_ascii.ply", false);
    write_ply_cloud(tile, out / "ply_cloud/tile_binary.ply", true);
    write_pcd(birch, out / "pcd/birch.pcd");
    pcd_seeds_from_pcl(birch, out);
    write_text_cloud(birch, out / "text_cloud/birch.xyz");
    write_text_cloud(tile, out / "text_cloud/tile.csv");
}

void skeleton_and_mesh_seeds(const fs::path& source, const fs::path& out) {
    const TreeGraph palm = read_skeleton_ply(source / "data/synthetic/palm_1_skeleton.ply");
    const TreeGraph small = first_nodes(palm, 40);
    write_skeleton_ply(small, out / "skeleton_ply/palm_binary.ply", true);
    write_skeleton_ply(small, out / "skeleton_ply/palm_ascii.ply", false);
    const TriangleMesh palm_mesh = read_mesh(source / "data/synthetic/palm_1_mesh.ply");
    // The first 60 faces with the vertices they use, renumbered.
    TriangleMesh mesh;
    mesh.origin = palm_mesh.origin;
    std::vector<int> index(palm_mesh.vertices.size(), -1);
    for (std::size_t f = 0; f < std::min<std::size_t>(palm_mesh.faces.size(), 60); ++f) {
        std::array<int, 3> face{};
        for (int k = 0; k < 3; ++k) {
            int& i = index[static_cast<std::size_t>(palm_mesh.faces[f][k])];
            if (i < 0) {
                i = static_cast<int>(mesh.vertices.size());
                mesh.vertices.push_back(palm_mesh.vertices[static_cast<std::size_t>(palm_mesh.faces[f][k])]);
            }
            face[k] = i;
        }
        mesh.faces.push_back(face);
    }
    // No STL writer in the project (OpenMesh reads it): an ascii STL by hand.
    std::ostringstream stl;
    stl << "solid palm\n";
    for (const auto& face : mesh.faces) {
        stl << "facet normal 0 0 1\n outer loop\n";
        for (int v : face) {
            const Eigen::Vector3f& p = mesh.vertices[static_cast<std::size_t>(v)];
            stl << "  vertex " << p.x() << " " << p.y() << " " << p.z() << "\n";
        }
        stl << " endloop\nendfacet\n";
    }
    stl << "endsolid palm\n";
    write_bytes(out / "mesh/palm.stl", std::string(1, '\2') + stl.str());
    // The mesh seeds carry the format-selecting first byte of mesh_fuzz.cpp (obj, off, stl, ply, glb).
    const char* extensions[] = {"obj", "off", "ply"};
    const char selector[] = {0, 1, 3};
    for (int k = 0; k < 3; ++k) {
        const fs::path file = out / "mesh" / (std::string("palm.") + extensions[k]);
        write_mesh(mesh, file);
        std::ifstream in(file, std::ios::binary);
        const std::string body((std::istreambuf_iterator<char>(in)), {});
        write_bytes(file, std::string(1, selector[k]) + body);
    }
    // glb through the export's writer: the faces as one tree's bark (with normals, a material, a node).
    const exporting::GltfTree tree{"palm", mesh.origin, {{mesh, {}, {}}}, {}, ""};
    write_bytes(out / "mesh/palm.glb", std::string(1, '\4') + exporting::glb_bytes({tree}, mesh.origin));
}

encode::StoredTree stored_code(const TreeGraph& tree, encode::Coder coder, int lods) {
    encode::TreeFileOptions options;
    options.encode.resolution = 4;
    options.coder = coder;
    options.lods = lods;
    return encode::store_tree(tree, options);
}

void code_seeds(const fs::path& source, const fs::path& out) {
    const TreeGraph birch = first_nodes(read_skeleton_ply(source / "data/synthetic/birch_3_skeleton.ply"), 120);
    for (const auto& [name, coder] : {std::pair{"best", encode::Coder::Best}, std::pair{"ic", encode::Coder::Interpolative}}) {
        const encode::StoredTree tree = stored_code(birch, coder, 3);
        write_bytes(out / "dbf6" / (std::string("birch_") + name + ".dbf6"), as_text(encode::write_tree_file_bytes(tree)));
        write_bytes(out / "dbf6_record" / (std::string("birch_") + name + ".record"), as_text(encode::write_tree_record(tree)));
        const encode::ChainCode& code = tree.lods.front();
        std::string radii;
        for (int r : code.radii) radii += (radii.empty() ? "" : ",") + std::to_string(r);
        write_bytes(out / "chain_code" / (std::string("birch_") + name + ".txt"), code.symbols + "\n" + radii);
    }
    std::vector<encode::ForestTree> trees;
    const char* species[] = {"birch_3", "lagerstroemia_2", "palm_1"};
    for (int i : {1, 2, 3}) {
        encode::ForestTree t;
        t.skeleton = first_nodes(read_skeleton_ply(source / "data/synthetic" / (std::string(species[i - 1]) + "_skeleton.ply")), 30);
        t.position = {100.0 * i, 50.0, 2.0};
        t.azimuth = 0.5f * i;
        t.name = "tree_" + std::to_string(i);
        trees.push_back(t);
    }
    encode::TreeFileOptions options;
    options.encode.resolution = 4;
    options.lods = 2;
    for (const auto& [name, coder] : {std::pair{"best", encode::Coder::Best}, std::pair{"ic", encode::Coder::Interpolative}}) {
        options.coder = coder;
        const auto bytes = encode::write_forest_bytes(trees, options);
        write_bytes(out / "forest" / (std::string("three_") + name + ".forest"), as_text(bytes));
        write_bytes(out / "forest_record" / (std::string("three_") + name + ".forest"), as_text(bytes));
    }
}

// A closed octahedron around `c` with half-size `r`, outward.
TriangleMesh octahedron(const Eigen::Vector3f& c, float r) {
    TriangleMesh m;
    m.vertices = {c + Eigen::Vector3f(r, 0, 0),  c + Eigen::Vector3f(-r, 0, 0), c + Eigen::Vector3f(0, r, 0),
                  c + Eigen::Vector3f(0, -r, 0), c + Eigen::Vector3f(0, 0, r),  c + Eigen::Vector3f(0, 0, -r)};
    m.faces = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4}, {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
    return m;
}

void tlobe_seeds(const fs::path& source, const fs::path& out) {
    lobes::LobeTree tree;
    tree.skeleton = first_nodes(read_skeleton_ply(source / "data/synthetic/lagerstroemia_2_skeleton.ply"), 30);
    tree.species = "lagerstroemia";
    tree.root_diameter = 2.0 * tree.skeleton.nodes[0].radius;
    for (int seed : {10, 20}) {
        lobes::Lobe lobe;
        lobe.seed_node = seed;
        lobe.mesh = octahedron(tree.skeleton.nodes[seed].position + Eigen::Vector3f(0, 0, 0.4f), 0.3f);
        for (int k = 0; k < 50; ++k)
            lobe.cluster_points.push_back(lobe.mesh.vertices[k % 6] * 0.9f + tree.skeleton.nodes[seed].position * 0.1f);
        lobe.points = lobe.cluster_points.size();
        tree.lobes.push_back(lobe);
    }
    const std::string file = lobes::encode_tlobe(tree);
    write_bytes(out / "tlobe/lagerstroemia.tlobe", file);
    // A budget one byte short of it: the lobes are stored without surfaces, which the reader
    // derives from their occupancy (version 6.0).
    lobes::TlobeOptions tight;
    tight.max_bytes = file.size() - 1;
    const std::string derived = lobes::encode_tlobe(tree, tight);
    write_bytes(out / "tlobe/lagerstroemia_derived.tlobe", derived);
    // The payload seeds: the inflated bytes behind the 20-byte header (docs/tlobe.md).
    const auto payload = [](const std::string& bytes) {
        std::uint32_t raw_size = 0;
        for (int i = 0; i < 4; ++i) raw_size |= static_cast<std::uint32_t>(static_cast<unsigned char>(bytes[8 + i])) << (8 * i);
        std::string raw(raw_size, '\0');
        uLongf unpacked = raw_size;
        uncompress(reinterpret_cast<Bytef*>(raw.data()), &unpacked, reinterpret_cast<const Bytef*>(bytes.data() + 20),
                   static_cast<uLong>(bytes.size() - 20));
        return raw;
    };
    write_bytes(out / "tlobe_payload/lagerstroemia.payload", payload(file));
    write_bytes(out / "tlobe_payload/lagerstroemia_derived.payload", payload(derived));
}

void jointboost_seeds(const fs::path& out) {
    classify::FeatureTable table;
    table.feature_names = {"height", "crown_ratio", "scan_density"};
    std::vector<int> labels;
    for (int i = 0; i < 40; ++i) {
        const double row[] = {10.0 + i % 7, (i % 2) ? 0.3 : 0.7, (i < 20) ? 50.0 : 5000.0};
        table.add_row("t" + std::to_string(i), row);
        labels.push_back(i % 2);
    }
    classify::JointBoostOptions options;
    options.max_rounds = 6;
    options.route_min_trees = 10;
    options.folds = 2;
    classify::save_jointboost(classify::train_jointboost(table, labels, {"pine", "birch"}, options), out / "jointboost/routed.json");
    options.route_by_scan = false;
    options.fold_ensemble = false;
    classify::save_jointboost(classify::train_jointboost(table, labels, {"pine", "birch"}, options), out / "jointboost/single.json");
}

// A file with the format-selecting first byte of qsm_fuzz.cpp / export_info_fuzz.cpp.
void write_selected(const fs::path& path, char selector, const std::string& body) { write_bytes(path, std::string(1, selector) + body); }

std::string file_text(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), {}};
}

void export_seeds(const fs::path& source, const fs::path& out) {
    exporting::ExportTree tree{"palm", first_nodes(read_skeleton_ply(source / "data/synthetic/palm_1_skeleton.ply"), 25), {}, "palm"};
    const QsmModel qsm = exporting::qsm_from_tree(tree.skeleton, tree.name);
    const fs::path scratch = out / "qsm/scratch";
    write_treeqsm_cylinders(qsm, scratch);
    write_selected(out / "qsm/palm_treeqsm.txt", 0, file_text(scratch));
    write_qsm_csv(qsm, scratch);
    write_selected(out / "qsm/palm_simpleforest.csv", 1, file_text(scratch));
    fs::remove(scratch);
    exporting::TreeGeometryOptions geometry;
    geometry.lods = 2;
    geometry.sides = 3;
    const exporting::GltfTree gltf{tree.name, tree.skeleton.origin, exporting::tree_lods(tree, geometry), {{"height", 1.0}}, tree.species};
    write_selected(out / "export_info/palm.glb", 0, exporting::glb_bytes({gltf}, tree.skeleton.origin));
    write_selected(out / "export_info/palm.city.json", 1, exporting::cityjson_text({tree}, "EPSG:25832"));
}

void text_seeds(const fs::path& source, const fs::path& out) {
    fs::create_directories(out / "species_yaml");
    fs::copy_file(source / "config/species.yaml", out / "species_yaml/species.yaml", fs::copy_options::overwrite_existing);
    fs::create_directories(out / "lsystem");
    for (const auto& entry : fs::directory_iterator(source / "lsystem/examples"))
        fs::copy_file(entry.path(), out / "lsystem" / entry.path().filename(), fs::copy_options::overwrite_existing);
}

// CRS texts as LAS files carry them: WKT 1 in feet and in metres, WKT 2, geographic, a WKT 2
// compound CRS with heights in feet.
void crs_seeds(const fs::path& out) {
    write_bytes(out / "crs_units/wkt1_feet.txt",
                R"wkt(PROJCS["Lambert (ft)",GEOGCS["NAD83",DATUM["D_North_American_1983",SPHEROID["GRS_1980",6378137,298.257222101]],)wkt"
                R"wkt(PRIMEM["Greenwich",0],UNIT["Degree",0.017453292519943295]],PROJECTION["Lambert_Conformal_Conic"],)wkt"
                R"wkt(PARAMETER["standard_parallel_1",43],UNIT["Foot_US",0.3048006096012192]])wkt");
    write_bytes(out / "crs_units/wkt1_compound_metre.txt",
                R"wkt(COMPD_CS["UTM 32N + height",PROJCS["ETRS89 / UTM zone 32N",GEOGCS["ETRS89",UNIT["degree",0.0174532925199433]],)wkt"
                R"wkt(UNIT["metre",1,AUTHORITY["EPSG","9001"]]],VERT_CS["DHHN2016 height",UNIT["metre",1]]])wkt");
    write_bytes(out / "crs_units/wkt2_feet.txt",
                R"wkt(PROJCRS["State Plane (ftUS)",BASEGEOGCRS["NAD83",ANGLEUNIT["degree",0.0174532925199433]],CONVERSION["SPCS",)wkt"
                R"wkt(PARAMETER["False easting",600000,LENGTHUNIT["metre",1]]],CS[Cartesian,2],)wkt"
                R"wkt(AXIS["easting (X)",east,LENGTHUNIT["US survey foot",0.304800609601219]]])wkt");
    write_bytes(out / "crs_units/geographic.txt", R"wkt(GEOGCRS["WGS 84",ENSEMBLE["World Geodetic System 1984"],CS[ellipsoidal,2]])wkt");
    write_bytes(out / "crs_units/wkt2_compound_height_feet.txt",
                R"wkt(COMPOUNDCRS["NAD83 / Oregon LCC (m) + NAVD88 height (ftUS)",PROJCRS["NAD83 / Oregon LCC (m)",CS[Cartesian,2],)wkt"
                R"wkt(AXIS["easting",east,LENGTHUNIT["metre",1]]],VERTCRS["NAVD88 height (ftUS)",VDATUM["NAVD88"],CS[vertical,1],)wkt"
                R"wkt(AXIS["gravity-related height (H)",up,LENGTHUNIT["US survey foot",0.304800609601219]]]])wkt");
}

}  // namespace

int main(int argc, char** argv) {
    if (argc != 3) {
        std::cerr << "usage: fuzz_make_seeds SOURCE_DIR OUT_DIR\n";
        return 1;
    }
    const fs::path source = argv[1], out = argv[2];
    for (const char* target : {"las", "ply_cloud", "skeleton_ply", "text_cloud", "pcd", "mesh", "dbf6", "dbf6_record", "chain_code",
                               "forest", "forest_record", "tlobe", "tlobe_payload", "jointboost", "qsm", "export_info", "crs_units"})
        fs::create_directories(out / target);
    cloud_seeds(source, out);
    skeleton_and_mesh_seeds(source, out);
    code_seeds(source, out);
    tlobe_seeds(source, out);
    jointboost_seeds(out);
    export_seeds(source, out);
    text_seeds(source, out);
    crs_seeds(out);
    return 0;
}
