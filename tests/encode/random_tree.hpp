// Deterministic random tree skeletons for the encode tests and the encode bench report, until
// the species synthesiser (synth/) provides trees of the configured species.
//
// Branches grow as chains of internodes of length l·(1 ± jitter) with a random turn per
// internode ("wiggle"; 0 = straight); an internode forks with some probability into the main
// continuation plus 1..max_laterals laterals (multi-way forks when more than one). Radii follow
// the pipe model (tip radius · √tips below). Numbers come from std::mt19937, whose output the
// standard fixes, through our own uniform mapping and shuffle (std:: distributions are
// implementation-defined), so a seed gives the same tree everywhere up to libm rounding.
#pragma once

#include "core/tree_graph.hpp"

#include <Eigen/Geometry>

#include <cmath>
#include <cstdint>
#include <deque>
#include <numeric>
#include <random>
#include <string>
#include <vector>

namespace treelobes::test {

struct RandomTreeProfile {
    std::string name = "random";
    int max_nodes = 300;
    double internode_length = 0.1;   // nominal l (metres)
    double length_jitter = 0.3;      // keep < 0.4: edges then span > 1.8 voxels at r >= 3
    double wiggle_degrees = 5.0;     // random turn per internode (0 = straight branches)
    double fork_probability = 0.25;  // chance that an internode with a continuation forks
    int max_laterals = 1;            // laterals per fork; > 1 gives multi-way forks
    double branch_angle_degrees = 45.0;
    int trunk_internodes = 20;
    double lateral_length_ratio = 0.6;  // lateral length relative to the parent's remaining length
    int max_order = 4;
    int root_stems = 1;         // children of the root (> 1: multi-stemmed)
    double tip_radius = 0.002;  // metres; the pipe model gives the rest
    bool shuffle = true;        // random node numbering and child order
};

class TreeRandom {
public:
    explicit TreeRandom(std::uint32_t seed) : engine_(seed) {}
    double uniform() { return engine_() * (1.0 / 4294967296.0); }  // [0, 1)
    double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
    int below(int n) { return static_cast<int>(uniform() * n); }  // [0, n)
    template <class Items>
    void shuffle(Items& items) {  // Fisher-Yates
        for (int i = static_cast<int>(items.size()) - 1; i > 0; --i) std::swap(items[i], items[below(i + 1)]);
    }

private:
    std::mt19937 engine_;
};

namespace detail {

inline Eigen::Vector3d any_perpendicular(const Eigen::Vector3d& d) {
    const Eigen::Vector3d helper = std::abs(d.z()) < 0.9 ? Eigen::Vector3d::UnitZ() : Eigen::Vector3d::UnitX();
    return d.cross(helper).normalized();
}

// `d` turned by `angle` (radians) towards a random azimuth.
inline Eigen::Vector3d turn(const Eigen::Vector3d& d, double angle, TreeRandom& random) {
    const Eigen::Vector3d e1 = any_perpendicular(d), e2 = d.cross(e1);
    const double azimuth = random.uniform(0.0, 2.0 * M_PI);
    return (std::cos(angle) * d + std::sin(angle) * (std::cos(azimuth) * e1 + std::sin(azimuth) * e2)).normalized();
}

struct Stem {
    int start;
    Eigen::Vector3d direction;
    int internodes;
    int order;
};

// Pipe model: tip radius · √(tips in the subtree).
inline std::vector<float> pipe_radii(const std::vector<int>& parent, double tip_radius) {
    std::vector<int> tips(parent.size(), 0);
    std::vector<int> children(parent.size(), 0);
    for (std::size_t i = 1; i < parent.size(); ++i) ++children[parent[i]];
    // Nodes are created after their parents, so a reverse sweep visits children first.
    for (std::size_t i = parent.size(); i-- > 0;) {
        if (children[i] == 0) tips[i] = 1;
        if (i > 0) tips[parent[i]] += tips[i];
    }
    std::vector<float> radii(parent.size());
    for (std::size_t i = 0; i < parent.size(); ++i) radii[i] = static_cast<float>(tip_radius * std::sqrt(tips[i]));
    return radii;
}

}  // namespace detail

inline TreeGraph random_tree(const RandomTreeProfile& profile, std::uint32_t seed) {
    TreeRandom random(seed);
    // Coordinates drawn one statement each, last first: the order GCC evaluated the arguments in
    // (C++ leaves it open; Clang goes left to right), so both compilers make the same points.
    const double root_z = random.uniform(0, 1), root_y = random.uniform(-5, 5), root_x = random.uniform(-5, 5);
    std::vector<Eigen::Vector3d> position{Eigen::Vector3d(root_x, root_y, root_z)};
    std::vector<int> parent{-1};
    const double wiggle = profile.wiggle_degrees * M_PI / 180.0;
    const double branch_angle = profile.branch_angle_degrees * M_PI / 180.0;

    std::deque<detail::Stem> stems;
    for (int s = 0; s < profile.root_stems; ++s) {
        const double tilt = profile.root_stems > 1 ? random.uniform(0.2, 0.6) : random.uniform(0.0, 0.1);
        stems.push_back({0, detail::turn(Eigen::Vector3d::UnitZ(), tilt, random), profile.trunk_internodes, 0});
    }
    while (!stems.empty() && static_cast<int>(position.size()) < profile.max_nodes) {
        const detail::Stem stem = stems.front();
        stems.pop_front();
        int node = stem.start;
        Eigen::Vector3d direction = stem.direction;
        for (int i = 0; i < stem.internodes && static_cast<int>(position.size()) < profile.max_nodes; ++i) {
            if (wiggle > 0) direction = detail::turn(direction, random.uniform(0.0, wiggle), random);
            const double length = profile.internode_length * (1.0 + profile.length_jitter * random.uniform(-1.0, 1.0));
            position.push_back(position[node] + direction * length);
            parent.push_back(node);
            node = static_cast<int>(position.size()) - 1;
            const int remaining = stem.internodes - 1 - i;
            if (remaining == 0 || stem.order >= profile.max_order || random.uniform() >= profile.fork_probability) continue;
            const int laterals = 1 + random.below(profile.max_laterals);
            for (int k = 0; k < laterals; ++k) {
                const double angle = branch_angle * random.uniform(0.7, 1.3);
                const int lateral_internodes =
                        std::max(1, static_cast<int>(remaining * profile.lateral_length_ratio * random.uniform(0.5, 1.2)));
                stems.push_back({node, detail::turn(direction, angle, random), lateral_internodes, stem.order + 1});
            }
        }
    }

    const std::vector<float> radii = detail::pipe_radii(parent, profile.tip_radius);
    // Node numbering: the root stays 0, the rest optionally permuted.
    std::vector<int> index(position.size());
    std::iota(index.begin(), index.end(), 0);
    if (profile.shuffle) {
        std::vector<int> rest(index.begin() + 1, index.end());
        random.shuffle(rest);
        std::copy(rest.begin(), rest.end(), index.begin() + 1);
    }
    TreeGraph tree;
    tree.nodes.resize(position.size());
    for (std::size_t i = 0; i < position.size(); ++i) {
        TreeNode& node = tree.nodes[index[i]];
        node.position = position[i].cast<float>();
        node.radius = radii[i];
        node.parent = i == 0 ? -1 : index[parent[i]];
        if (i > 0) tree.nodes[index[parent[i]]].children.push_back(index[i]);
    }
    if (profile.shuffle)
        for (TreeNode& node : tree.nodes) random.shuffle(node.children);
    return tree;
}

}  // namespace treelobes::test
