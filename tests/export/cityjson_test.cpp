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
    ExportTree lobed{"oak", test::sample_tree({500000, 5400000, 300}), {}, "Quercus robur"};
    TriangleMesh lobe = test::octahedron({1.2f, 0.2f, 2.6f}, 0.4f);
    lobe.origin = lobed.skeleton.origin;
    lobed.lobes.push_back(lobe);
    return {lobed, {"t2", test::sample_tree({500010.5, 5400004.25, 301}), {}, ""}};
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
    EXPECT_GT(oak["attributes"]["crownDiameter"].get<double>(), 1.5);
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
