// `treelobes convert` on the real LAZ files (label `real`): LAZ to LAS gives the uncompressed
// twin record for record, and the written file reads back with the twin's header fields.
#include "core/las_io.hpp"
#include "core/little_endian.hpp"
#include "support/test_support.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cstring>
#include <fstream>
#include <iterator>
#include <vector>

using namespace treelobes;
using treelobes::test::real_data;
using treelobes::test::run_cli;
using treelobes::test::TempDir;

namespace {
std::vector<char> file_bytes(const std::filesystem::path& path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}
}  // namespace

TEST(ConvertReal, LazBecomesItsUncompressedTwin) {
    const std::pair<const char*, const char*> twins[] = {
            {"laz/MixedConifer.laz", "lidr/MixedConifer.las"},   {"laz/pine.laz", "treels/pine.las"},
            {"laz/pine_plot.laz", "treels/pine_plot.las"},       {"laz/laspy/simple.laz", "laz/laspy/simple.las"},
            {"laz/laspy/extra.laz", "laz/laspy/extrabytes.las"}, {"laz/laspy/1_4_w_evlr.laz", "laz/laspy/1_4_w_evlr.las"}};
    TempDir dir;
    for (const auto& [laz, las] : twins) {
        const auto out = dir / "out.las";
        const auto result = run_cli("--json convert '" + real_data(laz).string() + "' --out '" + out.string() + "'");
        ASSERT_EQ(result.exit_code, 0) << laz << ": " << result.err;
        EXPECT_EQ(nlohmann::json::parse(result.out)["method"], "records");
        const LasRecords converted = read_las_records(out);
        const LasRecords twin = read_las_records(real_data(las));
        EXPECT_FALSE(converted.compressed) << laz;
        EXPECT_EQ(converted.point_format, twin.point_format) << laz;
        EXPECT_EQ(converted.minor, twin.minor) << laz;
        EXPECT_EQ(converted.point_count, twin.point_count) << laz;
        EXPECT_TRUE(converted.points == twin.points) << laz << ": point records differ from " << las;
        // Scale, offset and bounds as in the twin's header (bytes 131-226).
        EXPECT_EQ(std::memcmp(converted.header.data() + 131, twin.header.data() + 131, 96), 0) << laz;
        for (const RawVlr& r : converted.vlrs) EXPECT_NE(r.user_id, "laszip encoded") << laz;
        EXPECT_EQ(converted.evlrs.size(), twin.evlrs.size()) << laz;
        // These twins were written by the same tools, so the whole files agree byte for byte.
        EXPECT_TRUE(file_bytes(out) == file_bytes(real_data(las))) << laz << ": file differs from " << las;
    }
}

TEST(ConvertReal, CopcToPlyKeepsEveryPoint) {
    TempDir dir;
    const auto result =
            run_cli("--json convert '" + real_data("laz/laspy/simple.copc.laz").string() + "' --out '" + (dir / "c.ply").string() + "'");
    ASSERT_EQ(result.exit_code, 0) << result.err;
    EXPECT_EQ(nlohmann::json::parse(result.out)["points"], 1065);
}
