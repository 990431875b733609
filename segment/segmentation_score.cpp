#include "segment/segmentation_score.hpp"

#include "core/error.hpp"

#include <algorithm>
#include <map>

namespace treelobes {

namespace {

struct TreeStats {
    std::size_t points = 0;
    float height = 0;
    std::int32_t match = 0;
};

std::map<std::int32_t, TreeStats> tree_stats(std::span<const std::int32_t> ids, std::span<const float> heights) {
    std::map<std::int32_t, TreeStats> stats;
    for (std::size_t i = 0; i < ids.size(); ++i) {
        if (!ids[i]) continue;
        TreeStats& s = stats[ids[i]];
        ++s.points;
        s.height = std::max(s.height, heights[i]);
    }
    return stats;
}

std::size_t height_class(float height) { return height < 10 ? 0 : height < 20 ? 1 : 2; }

}  // namespace

SegmentationScore score_segmentation(std::span<const std::int32_t> reference, std::span<const std::int32_t> found,
                                     std::span<const float> height_above_ground, float min_height) {
    if (reference.size() != found.size() || reference.size() != height_above_ground.size())
        throw Error(ExitCode::Internal, "score_segmentation: label and height counts differ");
    auto truth = tree_stats(reference, height_above_ground);
    auto result = tree_stats(found, height_above_ground);
    std::map<std::pair<std::int32_t, std::int32_t>, std::size_t> overlap;
    for (std::size_t i = 0; i < reference.size(); ++i)
        if (reference[i] && found[i]) ++overlap[{reference[i], found[i]}];
    for (const auto& [pair, shared] : overlap) {
        TreeStats& t = truth[pair.first];
        TreeStats& f = result[pair.second];
        if (2 * shared >= t.points && 2 * shared >= f.points) {
            t.match = pair.second;
            f.match = pair.first;
        }
    }
    SegmentationScore score;
    score.by_height = {{"5-10 m"}, {"10-20 m"}, {"20+ m"}};
    for (const auto& [id, t] : truth) {
        if (t.height <= min_height) continue;
        ++score.reference_trees;
        score.matched += t.match != 0;
        ++score.by_height[height_class(t.height)].reference;
        score.by_height[height_class(t.height)].matched += t.match != 0;
    }
    for (const auto& [id, f] : result) {
        const bool matched_counted = f.match && truth[f.match].height > min_height;
        const bool matched_short = f.match && !matched_counted;
        if (matched_counted || (!matched_short && f.height > min_height)) {
            ++score.found_trees;
            ++score.by_height[height_class(matched_counted ? truth[f.match].height : f.height)].found;
        }
    }
    std::size_t counted = 0, right = 0;
    for (std::size_t i = 0; i < reference.size(); ++i) {
        if (!reference[i]) continue;
        const TreeStats& t = truth[reference[i]];
        if (t.height <= min_height) continue;
        ++counted;
        right += t.match != 0 && found[i] == t.match;
    }
    score.precision = score.found_trees ? static_cast<double>(score.matched) / score.found_trees : 0.0;
    score.recall = score.reference_trees ? static_cast<double>(score.matched) / score.reference_trees : 0.0;
    score.f1 = score.precision + score.recall > 0 ? 2 * score.precision * score.recall / (score.precision + score.recall) : 0.0;
    score.points_right = counted ? static_cast<double>(right) / counted : 0.0;
    return score;
}

}  // namespace treelobes
