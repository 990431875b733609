// Inputs whose headers promise more than memory holds are refused before loading, with a
// message naming the estimate (core/memory_limit.hpp).
#include "core/cloud_io.hpp"
#include "core/error.hpp"
#include "core/memory_limit.hpp"
#include "core/skeleton_io.hpp"
#include "support/test_support.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>

using namespace treelobes;
using treelobes::test::TempDir;

namespace {

PointCloud small_cloud(std::size_t n) {
    PointCloud cloud;
    cloud.origin = {500000.0, 4000000.0, 100.0};
    for (std::size_t i = 0; i < n; ++i) cloud.positions.emplace_back(0.01f * i, 0.02f * i, 0.5f);
    return cloud;
}

// The message of the Error that reading `path` throws ("" when it reads).
template <typename Read>
std::string error_message(Read&& read) {
    try {
        read();
    } catch (const Error& e) {
        EXPECT_EQ(e.code(), ExitCode::InvalidInput);
        return e.what();
    }
    return "";
}

// Sets TREELOBES_MAX_MEMORY for the lifetime of the object.
class MemoryCap {
public:
    explicit MemoryCap(const char* value) { setenv("TREELOBES_MAX_MEMORY", value, 1); }
    ~MemoryCap() { unsetenv("TREELOBES_MAX_MEMORY"); }
};

}  // namespace

// A LAS 1.4 file whose header counts 2^36 points of 20 bytes, backed by a sparse file of that
// size (1.5 TiB, no disk blocks): every count check against the file passes, only the memory
// estimate can stop the reader before it allocates ~1.6 TiB.
TEST(MemoryLimit, LasHeaderPromisingMorePointsThanMemoryIsRefusedBeforeLoading) {
    TempDir dir;
    const auto path = dir / "huge.las";
    PointCloud cloud = small_cloud(3);
    cloud.add_extra("treeID", AttributeType::Int32);  // extra bytes: written as LAS 1.4 (64-bit count)
    write_las(cloud, path);
    std::fstream file(path, std::ios::binary | std::ios::in | std::ios::out);
    char header[375] = {};
    file.read(header, sizeof header);
    ASSERT_EQ(header[25], 4) << "a cloud with extra bytes is written as LAS 1.4";
    std::uint32_t offset_to_points = 0;
    std::uint16_t record_length = 0;
    std::memcpy(&offset_to_points, header + 96, 4);
    std::memcpy(&record_length, header + 105, 2);
    const std::uint64_t count = std::uint64_t{1} << 36;
    const std::uint32_t legacy = 0;
    file.seekp(107);
    file.write(reinterpret_cast<const char*>(&legacy), 4);
    file.seekp(247);
    file.write(reinterpret_cast<const char*>(&count), 8);
    file.close();
    std::filesystem::resize_file(path, offset_to_points + count * record_length);

    const std::string message = error_message([&] { read_las(path); });
    EXPECT_NE(message.find("68719476736 points"), std::string::npos) << message;
    EXPECT_NE(message.find("needs about"), std::string::npos) << message;
    EXPECT_NE(message.find("GiB of memory"), std::string::npos) << message;
}

TEST(MemoryLimit, CapFromTheEnvironmentAppliesToLasAndPly) {
    TempDir dir;
    write_las(small_cloud(2000), dir / "cloud.las");
    write_ply_cloud(small_cloud(2000), dir / "cloud.ply");
    {
        const MemoryCap cap("16K");
        const std::string las = error_message([&] { read_las(dir / "cloud.las"); });
        EXPECT_NE(las.find("the header's 2000 points needs about"), std::string::npos) << las;
        EXPECT_NE(las.find("TREELOBES_MAX_MEMORY allows"), std::string::npos) << las;
        const std::string ply = error_message([&] { read_ply_cloud(dir / "cloud.ply"); });
        EXPECT_NE(ply.find("2000 vertex items needs about"), std::string::npos) << ply;
    }
    EXPECT_EQ(read_las(dir / "cloud.las").size(), 2000u);
    const MemoryCap generous("1G");
    EXPECT_EQ(read_ply_cloud(dir / "cloud.ply").size(), 2000u);
}

TEST(MemoryLimit, MalformedCapIsAUsageError) {
    const MemoryCap cap("lots");
    EXPECT_EQ(test::error_code_of([] { memory_limit(); }), ExitCode::Usage);
}
