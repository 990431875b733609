// Spatial voting (Livny et al. 2011, §6.1): trees in towns are planted in same-species groups, so an
// uncertain tree borrows the opinion of its confident neighbours.
//   - A tree is confident when h1 > factor * h2 (h1, h2: its two highest class probabilities).
//   - A confident tree keeps its most probable species.
//   - Otherwise the species of the confident trees within `radius_m` form a candidate set and the
//     tree takes the candidate its own classifier finds most probable; with no confident
//     neighbour it keeps its most probable species.
// Positions are horizontal coordinates in one frame (metres).
#pragma once

#include <Eigen/Core>

#include <vector>

namespace treelobes::classify {

struct VotingOptions {
    double confidence_factor = 1.5;  // h1 > factor * h2
    double radius_m = 25.0;          // neighbourhood (2-3 typical crown diameters)
};

bool is_confident(const std::vector<double>& probabilities, double factor);

struct VotingResult {
    std::vector<int> species;     // voted class per tree
    std::vector<bool> confident;  // per tree
    std::vector<bool> changed;    // the vote replaced the tree's own most probable class
};

// Throws Error(Usage) for a factor below 1 or a negative radius; positions and probabilities
// must have the same length.
VotingResult spatial_vote(const std::vector<std::vector<double>>& probabilities, const std::vector<Eigen::Vector2d>& positions,
                          const VotingOptions& options);

}  // namespace treelobes::classify
