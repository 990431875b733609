// CityJSON 2.0 of trees: the official 2.0.2 schemas (ajv) accept it, our own checks (indices in
// range, closed solids) pass, and both catch broken documents.
#include "core/atomic_file.hpp"
#include "core/georef_sidecar.hpp"
#include "export/cityjson.hpp"
#include "sample_trees.hpp"
#include "support/test_support.hpp"
#include "validators.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

using namespace treelobes;
using namespace treelobes::exporting;

namespace {

std::vector<ExportTree> two_trees() {
    ExportTree lobed{"oak", test::sample_tree({500000, 5400000, 300}), {}, "Quercus robur", {}};
    TriangleMesh lobe = test::octahedron({1.2f, 0.2f, 2.6f}, 0.4f);
    lobe.origin = lobed.skeleton.origin;
    lobed.lobes.push_back(lobe);
    return {lobed, {"t2", test::sample_tree({500010.5, 5400004.25, 301}), {}, "", {}}};
}

void expect_schema_valid(const std::string& text, const test::TempDir& dir) {
    write_file_atomically(dir / "trees.city.json", text);
    const test::ValidatorRun run = test::validate_cityjson(dir / "trees.city.json");
    ASSERT_TRUE(run.available);
    EXPECT_EQ(run.exit_code, 0) << run.output;
}

}  // namespace

TEST(CityJson, TwoTreesAreSchemaValidWithClosedCrownsAndAttributes) {
    test::TempDir dir;
    const std::string text = cityjson_text(two_trees(), "EPSG:25832");
    EXPECT_EQ(text, cityjson_text(two_trees(), "EPSG:25832"));  // deterministic
    expect_schema_valid(text, dir);
    EXPECT_TRUE(check_cityjson(text).empty()) << check_cityjson(text).front();

    const auto doc = nlohmann::json::parse(text);
    EXPECT_EQ(doc["version"], "2.0");
    EXPECT_EQ(doc["metadata"]["referenceSystem"], "https://www.opengis.net/def/crs/EPSG/0/25832");
    // The floored minimum corner of the nodes widened by their radii (12 cm at the base).
    EXPECT_EQ(doc["transform"]["translate"], nlohmann::json({499999.0, 5399999.0, 299.0}));
    ASSERT_EQ(doc["CityObjects"].size(), 2u);
    const auto& oak = doc["CityObjects"]["oak"];
    EXPECT_EQ(oak["type"], "SolitaryVegetationObject");
    EXPECT_EQ(oak["attributes"]["species"], "Quercus robur");
    EXPECT_NEAR(oak["attributes"]["height"].get<double>(), 3.0, 1e-3);
    EXPECT_NEAR(oak["attributes"]["trunkDiameter"].get<double>(), 0.19, 1e-3);
    // The circle with the area of the crown seen from above (1.17 m^2: the branches and the lobe
    // reaching 1.6 m east of the trunk): 1.22 m, where the mean of its x and y extents is over 1.5 m.
    EXPECT_NEAR(oak["attributes"]["crownDiameter"].get<double>(), 1.222, 0.002);
    EXPECT_EQ(oak["attributes"]["lobeCount"], 1);
    EXPECT_FALSE(doc["CityObjects"]["t2"]["attributes"].contains("species"));
    ASSERT_EQ(oak["geometry"].size(), 2u);
    EXPECT_EQ(oak["geometry"][0]["type"], "Solid");
    EXPECT_EQ(oak["geometry"][0]["lod"], "1");
    EXPECT_EQ(oak["geometry"][1]["type"], "MultiSurface");
    EXPECT_EQ(oak["geometry"][1]["lod"], "2");
    // Real coordinates of the extent: the oak's base at (500000, 5400000, 300) minus the trunk radius.
    const auto& extent = doc["metadata"]["geographicalExtent"];
    EXPECT_NEAR(extent[0].get<double>(), 500000 - 0.8 - 0.05, 0.1);
    EXPECT_NEAR(extent[5].get<double>(), 301 + 3.0, 0.2);
}

TEST(CityJson, BrokenDocumentsAreCaught) {
    test::TempDir dir;
    auto doc = nlohmann::json::parse(cityjson_text(two_trees(), ""));
    EXPECT_FALSE(doc["metadata"].contains("referenceSystem"));  // no CRS known
    // Our checks: an open crown (one face less) and an index past the vertex list.
    auto open = doc;
    open["CityObjects"]["oak"]["geometry"][0]["boundaries"][0].erase(0);
    EXPECT_FALSE(check_cityjson(open.dump()).empty());
    auto out_of_range = doc;
    out_of_range["CityObjects"]["t2"]["geometry"][1]["boundaries"][0][0][0] = doc["vertices"].size();
    EXPECT_FALSE(check_cityjson(out_of_range.dump()).empty());
    // The schema: not a CityJSON city object type.
    auto wrong_type = doc;
    wrong_type["CityObjects"]["oak"]["type"] = "Tree";
    write_file_atomically(dir / "wrong.city.json", wrong_type.dump());
    const test::ValidatorRun run = test::validate_cityjson(dir / "wrong.city.json");
    ASSERT_TRUE(run.available);
    EXPECT_EQ(run.exit_code, 1) << run.output;
}

TEST(CityJson, EpsgCodeFromShortFormsAndWkt) {
    EXPECT_EQ(epsg_code("EPSG:25832"), "25832");
    EXPECT_EQ(epsg_code("PROJCS[\"WGS 84 / UTM zone 33N\",GEOGCS[\"WGS 84\",AUTHORITY[\"EPSG\",\"4326\"]],"
                        "UNIT[\"metre\",1,AUTHORITY[\"EPSG\",\"9001\"]],AUTHORITY[\"EPSG\",\"32633\"]]"),
              "32633");
    EXPECT_EQ(epsg_code("PROJCRS[\"ETRS89 / UTM 32N\",BASEGEOGCRS[\"ETRS89\",ID[\"EPSG\",4258]],ID[\"EPSG\",25832]]"), "25832");
    EXPECT_EQ(epsg_code("LOCAL_CS[\"site\"]"), "");
    EXPECT_EQ(epsg_code(""), "");
}

namespace {

// The sample tree 1.5 times as large in every direction (radii too).
TreeGraph scaled_sample_tree(const Eigen::Vector3d& origin, float factor) {
    TreeGraph tree = test::sample_tree(origin);
    for (auto& node : tree.nodes) {
        node.position *= factor;
        node.radius *= factor;
    }
    return tree;
}

}  // namespace

TEST(CityJson, InstancesOneTemplatePerSpeciesScaledToEachTree) {
    test::TempDir dir;
    std::vector<ExportTree> trees = two_trees();  // "oak" (Quercus robur, 3 m) and "t2" (no species)
    trees.push_back({"oak_big", scaled_sample_tree({500020, 5400000, 302}, 1.5f), {}, "Quercus robur", {}});
    CityJsonOptions options;
    options.instances = true;
    const std::string text = cityjson_text(trees, "EPSG:25832", options);
    EXPECT_EQ(text, cityjson_text(trees, "EPSG:25832", options));  // deterministic
    expect_schema_valid(text, dir);
    EXPECT_TRUE(check_cityjson(text).empty()) << check_cityjson(text).front();

    const auto doc = nlohmann::json::parse(text);
    const auto& templates = doc["geometry-templates"]["templates"];
    ASSERT_EQ(templates.size(), 2u);  // sorted by species: "" (no species) first, then Quercus robur
    for (const auto& t : templates) {
        EXPECT_EQ(t["type"], "MultiSurface");
        EXPECT_EQ(t["lod"], "2");
    }
    // The oak template is the lower-middle oak by height: the 3 m one, relative to its stem base.
    double bottom = 1e9, top = -1e9;
    for (const auto& surface : templates[1]["boundaries"])
        for (const auto& index : surface[0]) {
            const double z = doc["geometry-templates"]["vertices-templates"][index.get<std::size_t>()][2].get<double>();
            bottom = std::min(bottom, z), top = std::max(top, z);
        }
    EXPECT_NEAR(bottom, 0.0, 0.01);
    EXPECT_NEAR(top, 3.0, 0.05);  // not the 4.5 m oak
    const auto translate = doc["transform"]["translate"];
    const auto reference_point = [&](const nlohmann::json& instance) {
        const auto& v = doc["vertices"][instance["boundaries"][0].get<std::size_t>()];
        return Eigen::Vector3d(translate[0].get<double>() + 0.001 * v[0].get<double>(),
                               translate[1].get<double>() + 0.001 * v[1].get<double>(),
                               translate[2].get<double>() + 0.001 * v[2].get<double>());
    };
    const auto instance_of = [&](const std::string& name) {
        const auto& geometry = doc["CityObjects"][name]["geometry"];
        EXPECT_EQ(geometry.size(), 2u) << name;  // the tree's own LoD 1 crown and the instance
        EXPECT_EQ(geometry[0]["type"], "Solid");
        return geometry.back();
    };
    const auto oak = instance_of("oak"), big = instance_of("oak_big"), t2 = instance_of("t2");
    EXPECT_EQ(oak["type"], "GeometryInstance");
    EXPECT_EQ(oak["template"], 1);
    EXPECT_EQ(big["template"], 1);
    EXPECT_EQ(t2["template"], 0);
    // The reference points are the stem bases; the matrices scale the template to each tree.
    EXPECT_LT((reference_point(oak) - Eigen::Vector3d(500000, 5400000, 300)).norm(), 2e-3);
    EXPECT_LT((reference_point(big) - Eigen::Vector3d(500020, 5400000, 302)).norm(), 2e-3);
    const auto identity = nlohmann::json({1.0, 0, 0, 0, 0, 1.0, 0, 0, 0, 0, 1.0, 0, 0, 0, 0, 1});
    EXPECT_EQ(oak["transformationMatrix"], identity);
    EXPECT_NEAR(big["transformationMatrix"][10].get<double>(), 1.5, 1e-3);  // height ratio
    const auto crown = [&](const std::string& name) { return doc["CityObjects"][name]["attributes"]["crownDiameter"].get<double>(); };
    EXPECT_NEAR(big["transformationMatrix"][0].get<double>(), crown("oak_big") / crown("oak"), 1e-3);  // crown diameter ratio
    EXPECT_EQ(big["transformationMatrix"][0], big["transformationMatrix"][5]);
    EXPECT_EQ(t2["transformationMatrix"], identity);  // its own template

    // Our checks catch what the schema cannot: a template index or reference point out of range.
    auto bad_template = doc;
    bad_template["CityObjects"]["oak"]["geometry"][1]["template"] = 2;
    EXPECT_FALSE(check_cityjson(bad_template.dump()).empty());
    auto bad_reference = doc;
    bad_reference["CityObjects"]["oak"]["geometry"][1]["boundaries"][0] = doc["vertices"].size();
    EXPECT_FALSE(check_cityjson(bad_reference.dump()).empty());
    auto bad_template_vertex = doc;
    bad_template_vertex["geometry-templates"]["templates"][0]["boundaries"][0][0][0] =
            doc["geometry-templates"]["vertices-templates"].size();
    EXPECT_FALSE(check_cityjson(bad_template_vertex.dump()).empty());
    // The schema catches a matrix of 15 numbers.
    auto short_matrix = doc;
    short_matrix["CityObjects"]["oak"]["geometry"][1]["transformationMatrix"].erase(15);
    write_file_atomically(dir / "short.city.json", short_matrix.dump());
    const test::ValidatorRun run = test::validate_cityjson(dir / "short.city.json");
    ASSERT_TRUE(run.available);
    EXPECT_EQ(run.exit_code, 1) << run.output;
}
