#include "classify/batch.hpp"

#include "core/cloud_io.hpp"
#include "core/error.hpp"
#include "core/log.hpp"
#include "core/parallel.hpp"

#include <chrono>
#include <cmath>
#include <ctime>
#include <map>
#include <mutex>

namespace treelobes::classify {

std::vector<std::pair<long long, PointCloud>> split_trees(const PointCloud& cloud, const std::string& attribute, const std::string& file) {
    const ExtraAttribute* ids = cloud.extra(attribute);
    if (!ids) throw Error::input(file, "no per-point attribute '" + attribute + "' to split trees by");
    std::map<long long, std::vector<std::size_t>> members;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        const double v = ids->values[i];
        if (!std::isfinite(v) || v == 0 || (ids->no_data && v == *ids->no_data) || std::abs(v) > 9e15) continue;
        members[std::llround(v)].push_back(i);
    }
    std::vector<std::pair<long long, PointCloud>> trees;
    for (const auto& [id, indices] : members) trees.emplace_back(id, cloud.subset(indices));
    return trees;
}

namespace {

struct Tree {
    std::string id;
    PointCloud cloud;
};

Eigen::Vector2d mean_position(const PointCloud& cloud) {
    Eigen::Vector2d sum = Eigen::Vector2d::Zero();
    for (const auto& p : cloud.positions) sum += p.head<2>().cast<double>();
    return cloud.origin.head<2>() + sum / static_cast<double>(std::max<std::size_t>(1, cloud.size()));
}

}  // namespace

std::string crown_counts_json(const std::vector<CrownCounts>& crowns) {
    std::size_t input = 0, noise = 0, ground = 0, outliers = 0, understorey = 0, without_ground = 0, without_shape = 0;
    for (const auto& c : crowns) {
        input += c.input, noise += c.noise, ground += c.ground, outliers += c.high_outliers, understorey += c.understorey;
        without_ground += !c.ground_found, without_shape += !c.shape_features;
    }
    return "{\"points\": " + std::to_string(input) + ", \"noise\": " + std::to_string(noise) + ", \"ground\": " + std::to_string(ground) +
           ", \"high_outliers\": " + std::to_string(outliers) + ", \"understorey\": " + std::to_string(understorey) +
           ", \"trees_without_ground_returns\": " + std::to_string(without_ground) +
           ", \"trees_without_shape_features\": " + std::to_string(without_shape) + "}";
}

std::string crown_counts_csv(const FeatureBatch& batch) {
    std::string csv = "id,points,noise,ground,high_outliers,understorey,ground_found,shape_features\n";
    for (std::size_t r = 0; r < batch.crowns.size(); ++r) {
        const CrownCounts& c = batch.crowns[r];
        csv += batch.table.ids[r] + "," + std::to_string(c.input) + "," + std::to_string(c.noise) + "," + std::to_string(c.ground) + "," +
               std::to_string(c.high_outliers) + "," + std::to_string(c.understorey) + "," + (c.ground_found ? "1" : "0") + "," +
               (c.shape_features ? "1" : "0") + "\n";
    }
    return csv;
}

FeatureBatch compute_feature_batch(const std::vector<BatchInput>& inputs, const FeatureOptions& options) {
    const auto start = std::chrono::steady_clock::now();
    const std::clock_t cpu_start = std::clock();
    FeatureBatch batch;
    batch.table.feature_names = feature_names();
    std::mutex mutex;
    Progress progress("classify features", inputs.size());
    // Per input: its rows (id, values, position) or failures, merged in input order afterwards
    // so the table does not depend on the thread schedule.
    struct Result {
        std::vector<std::string> ids;
        std::vector<std::vector<double>> rows;
        std::vector<Eigen::Vector2d> positions;
        std::vector<CrownCounts> crowns;
        std::vector<BatchFailure> failures;
        std::size_t points = 0;
        double seconds = 0;
    };
    std::vector<Result> results(inputs.size());
    treelobes::parallel_for(std::size_t(0), inputs.size(), [&](std::size_t k) {
        const BatchInput& input = inputs[k];
        Result& r = results[k];
        std::vector<Tree> trees;
        try {
            PointCloud cloud = read_point_cloud(input.file);
            r.points = cloud.size();
            if (input.tree_attribute.empty())
                trees.push_back({input.id, std::move(cloud)});
            else
                for (auto& [tree_id, tree] : split_trees(cloud, input.tree_attribute, input.file.string()))
                    trees.push_back({input.id + "/" + std::to_string(tree_id), std::move(tree)});
        } catch (const Error& e) {
            r.failures.push_back({input.id, e.what()});
        }
        for (const auto& tree : trees) {
            try {
                const auto t0 = std::chrono::steady_clock::now();
                CrownCounts crown;
                r.rows.push_back(compute_features(tree.cloud, options, tree.id, nullptr, &crown));
                r.crowns.push_back(crown);
                r.seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
                r.ids.push_back(tree.id);
                r.positions.push_back(mean_position(tree.cloud));
            } catch (const Error& e) {
                if (e.code() == ExitCode::Internal) throw;
                r.failures.push_back({tree.id, e.what()});
            }
        }
        std::lock_guard<std::mutex> lock(mutex);
        progress.advance();
    });
    progress.finish();
    for (auto& r : results) {
        for (std::size_t i = 0; i < r.ids.size(); ++i) {
            batch.table.add_row(r.ids[i], r.rows[i]);
            batch.positions.push_back(r.positions[i]);
            batch.crowns.push_back(r.crowns[i]);
        }
        for (auto& f : r.failures) {
            log_warn(f.id + ": " + f.reason);
            batch.failures.push_back(std::move(f));
        }
        batch.points += r.points;
        batch.feature_seconds += r.seconds;
    }
    batch.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    batch.cpu_seconds = static_cast<double>(std::clock() - cpu_start) / CLOCKS_PER_SEC;
    return batch;
}

}  // namespace treelobes::classify
