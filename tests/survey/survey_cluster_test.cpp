// A real one-node Slurm cluster (tests/survey/local_slurm_cluster.sh: munged, slurmctld, slurmd
// from the Debian packages, stopped by their pids on any exit) runs the shipped job-array script
// scripts/slurm/batch.sbatch with `sbatch --array=0-3 --wait`; the merged shards must be
// byte-identical to one unsharded run.
#include "support/test_support.hpp"
#include "survey_fixture.hpp"

#include <gtest/gtest.h>
#include <signal.h>
#include <nlohmann/json.hpp>

using namespace treelobes;
using namespace treelobes::test;
namespace fs = std::filesystem;

TEST(SurveyCluster, SlurmJobArrayMergesToTheBytesOfOneRun) {
    ASSERT_EQ(shell("command -v slurmctld slurmd munged sbatch >/dev/null"), 0)
            << "the cluster test needs the Debian packages slurm-wlm and munge (scripts/setup.sh)";
    TempDir dir;
    const fs::path tiles = make_survey(dir.path(), 4, 3, 20.0);
    const std::string batch = cli() + " --log-level warn batch '" + tiles.string() + "' --out '" + (dir / "single").string() + "' " +
                              kTileOptions + " >/dev/null";
    ASSERT_EQ(shell(batch), 0);
    ASSERT_EQ(shell(cli() + " merge '" + (dir / "single").string() + "' --out '" + (dir / "single_merged").string() + "' >/dev/null"), 0);

    const std::string source = TREELOBES_SOURCE_DIR;
    const std::string bin = fs::path(TREELOBES_CLI).parent_path().string();
    fs::create_directories(dir / "jobs");
    const std::string array = "cd '" + (dir / "jobs").string() + "' && PATH='" + bin +
                              "':$PATH sbatch --array=0-3 --wait --mem=1G --export=ALL,TILES='" + tiles.string() + "',OUT='" +
                              (dir / "sharded").string() + "',MAX_MEMORY=900M,TILE_OPTIONS='" + kTileOptions + "' '" + source +
                              "/scripts/slurm/batch.sbatch'";
    const std::string command = "'" + source + "/tests/survey/local_slurm_cluster.sh' '" + (dir / "cluster").string() + "' sh -c \"" +
                                array + "\" >'" + (dir / "cluster.out").string() + "' 2>&1";
    const int status = shell(command);
    ASSERT_EQ(status, 0) << file_bytes(dir / "cluster.out") << "\nslurmctld.log:\n"
                         << file_bytes(dir / "cluster" / "log" / "slurmctld.log");
    // Four array tasks ran, each one shard.
    int logs = 0;
    for (const auto& entry : fs::directory_iterator(dir / "jobs"))
        logs += entry.path().filename().string().rfind("treelobes-batch-", 0) == 0;
    EXPECT_EQ(logs, 4);
    // The daemons are gone: their pid files are removed or name no live process.
    for (const fs::path& pid_file :
         {dir / "cluster" / "munge" / "munged.pid", dir / "cluster" / "slurmctld.pid", dir / "cluster" / "slurmd.pid"}) {
        if (!fs::exists(pid_file)) continue;
        const pid_t pid = static_cast<pid_t>(std::stol(file_bytes(pid_file)));
        EXPECT_NE(kill(pid, 0), 0) << pid_file << ": process " << pid << " still runs";
    }

    ASSERT_EQ(shell(cli() + " merge '" + (dir / "sharded").string() + "' --out '" + (dir / "sharded_merged").string() + "' >/dev/null"), 0);
    expect_same_merge(dir / "single_merged", dir / "sharded_merged");
}
