// LAZ decoding speed (points per second): full record decoding of point formats 1/3 with one and
// two threads (chunks decode in parallel), and full versus selective (x y z + classification)
// decoding of the layered LAS 1.4 formats. Best of several runs, printed as a table.
// Usage: bench_laz_decode DATA_DIR   (DATA_DIR = ../shared/data)
#include "core/cloud_io.hpp"
#include "core/error.hpp"
#include "core/las_io.hpp"

#include <tbb/global_control.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <functional>

using namespace treelobes;

namespace {

// Best wall time of `runs` calls, in seconds.
double best_seconds(int runs, const std::function<void()>& action) {
    double best = 1e30;
    for (int r = 0; r < runs; ++r) {
        const auto start = std::chrono::steady_clock::now();
        action();
        best = std::min(best, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    }
    return best;
}

void full_decode(const std::filesystem::path& file) {
    const std::size_t points = read_las_records(file).point_count;
    double seconds[2] = {};
    for (int threads : {1, 2}) {
        const tbb::global_control limit(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(threads));
        seconds[threads - 1] = best_seconds(5, [&] { read_las_records(file); });
    }
    std::printf("%-28s %9zu  %12.0f  %12.0f  %7.2fx\n", file.filename().c_str(), points, points / seconds[0], points / seconds[1],
                seconds[0] / seconds[1]);
}

void selective_decode(const std::filesystem::path& file) {
    const tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
    CloudReadOptions lean;
    lean.xyz_classification_only = true;
    const std::size_t points = read_point_cloud(file).size();
    const double full = best_seconds(30, [&] { read_point_cloud(file); });
    const double selective = best_seconds(30, [&] { read_point_cloud(file, lean); });
    std::printf("%-28s %9zu  %12.0f  %12.0f  %7.2fx\n", file.filename().c_str(), points, points / full, points / selective,
                full / selective);
}

}  // namespace

int main(int argc, char** argv) {
    if (argc != 2) {
        std::fprintf(stderr, "usage: %s DATA_DIR\n", argv[0]);
        return 1;
    }
    const std::filesystem::path data = argv[1];
    try {
        std::printf("full decode to LAS records      points   1 thread pt/s  2 threads pt/s  speed-up\n");
        full_decode(data / "laz/laspy/autzen_trim.laz");
        full_decode(data / "laz/pine_plot.laz");
        full_decode(data / "laz/MixedConifer.laz");
        std::printf("\nLAS 1.4 layered, 1 thread        points     full pt/s  xyz+class pt/s  speed-up\n");
        selective_decode(data / "laz/laspy/simple.copc.laz");
        selective_decode(data / "laz/laspy/1_4_w_evlr.laz");
    } catch (const Error& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return 2;
    }
    return 0;
}
