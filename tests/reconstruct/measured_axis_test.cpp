// Nodes the skeleton placed on a branch axis measured by circle or slab fits stay there through
// the later re-centring of thin internodes (reconstruct_tree): on a sparse or one-sided scan of a
// thick stem an internode may hold only a patch of bark, whose centre is not the stem's.
#include "reconstruct/reconstruct_tree.hpp"
#include "reconstruct/skeleton.hpp"
#include "support/synthetic_clouds.hpp"

#include <gtest/gtest.h>

#include <algorithm>

using namespace treelobes;
using test::Segment;

namespace {

// Median distance of the inner nodes from the true axes.
float median_error(const TreeGraph& tree, const std::vector<Segment>& truth) {
    std::vector<float> error;
    for (std::size_t i = 1; i + 1 < tree.size(); ++i) error.push_back(test::distance_to_axes(tree.nodes[i].position, truth));
    std::nth_element(error.begin(), error.begin() + static_cast<long>(error.size() / 2), error.end());
    return error[error.size() / 2];
}

}  // namespace

TEST(MeasuredAxis, SkeletonFlagsNodesOnFittedStemsOnly) {
    // A 0.3 m stem scanned on its +x half (circle fits place it) carrying a 3 cm twig (centroids).
    const std::vector<Segment> truth{{{0, 0, 0}, {0, 0, 4}, 0.3f}, {{0.3f, 0, 2}, {1.8f, 0, 3.0f}, 0.03f}};
    const PointCloud cloud = test::cloud_from(truth, 1500, 11, 0.5f);
    const SkeletonResult r = reconstruct_skeleton(cloud.positions, {});
    ASSERT_EQ(r.node_on_axis.size(), r.tree.size());
    std::size_t stem = 0, stem_flagged = 0, twig = 0, twig_flagged = 0;
    for (std::size_t u = 0; u < r.tree.size(); ++u) {
        const Eigen::Vector3f& p = r.tree.nodes[u].position;
        if (p.x() > 0.6f) {
            ++twig;
            twig_flagged += r.node_on_axis[u];
        } else if (p.z() > 0.5f && p.z() < 3.5f && std::abs(p.x()) < 0.1f) {
            ++stem;
            stem_flagged += r.node_on_axis[u];
        }
    }
    ASSERT_GT(stem, 10u);
    ASSERT_GT(twig, 5u);
    EXPECT_GE(4 * stem_flagged, 3 * stem);  // most of the stem: some slices are too sparse for a trusted fit
    EXPECT_EQ(twig_flagged, 0u);
}

TEST(MeasuredAxis, RecentringLeavesNodesOnAMeasuredAxis) {
    // The one-sided stem again; re-centring is set to move every node with points onto them (no
    // thickness limit, no band around the points' centroid): the stem's nodes must stay on the
    // axis the circle fits found, 0.19 m from the centroid of the half ring's bark.
    const std::vector<Segment> truth{{{0, 0, 0}, {0, 0, 4}, 0.3f}};
    const PointCloud cloud = test::cloud_from(truth, 1500, 11, 0.5f);
    ReconstructOptions o;
    o.recentre.max_spread = 10.0f;
    o.recentre.inside_band = 0.0;
    o.recentre.dead_band = 0.0;
    const TreeReconstruction r = reconstruct_tree(cloud, o);
    EXPECT_LT(median_error(r.skeleton, truth), 0.06f);
    EXPECT_GT(r.summary.recentred_nodes, 0u);  // nodes off the measured axis still move
}
