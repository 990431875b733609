#include "classify/voting.hpp"

#include "core/error.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <set>

namespace treelobes::classify {

namespace {

int argmax(const std::vector<double>& p) { return static_cast<int>(std::max_element(p.begin(), p.end()) - p.begin()); }

// Trees per grid cell of side `radius`, so each neighbourhood query reads 3 x 3 cells.
using Grid = std::map<std::pair<long, long>, std::vector<std::size_t>>;
std::pair<long, long> cell_of(const Eigen::Vector2d& p, double size) {
    return {static_cast<long>(std::floor(p.x() / size)), static_cast<long>(std::floor(p.y() / size))};
}

}  // namespace

bool is_confident(const std::vector<double>& p, double factor) {
    if (p.size() < 2) return true;
    double first = -std::numeric_limits<double>::infinity(), second = first;  // the two largest
    for (double v : p) {
        if (v > first) {
            second = first;
            first = v;
        } else if (v > second) {
            second = v;
        }
    }
    return first > factor * second;
}

VotingResult spatial_vote(const std::vector<std::vector<double>>& probabilities, const std::vector<Eigen::Vector2d>& positions,
                          const VotingOptions& options) {
    if (!(options.confidence_factor >= 1.0)) throw Error::usage("voting: the confidence factor must be at least 1");
    if (!(options.radius_m >= 0.0)) throw Error::usage("voting: the radius must not be negative");
    if (probabilities.size() != positions.size())
        throw Error(ExitCode::Internal,
                    "voting: " + std::to_string(positions.size()) + " positions for " + std::to_string(probabilities.size()) + " trees");
    const std::size_t n = probabilities.size();
    VotingResult r;
    r.species.resize(n);
    r.confident.resize(n);
    r.changed.assign(n, false);
    for (std::size_t i = 0; i < n; ++i) {
        r.species[i] = argmax(probabilities[i]);
        r.confident[i] = is_confident(probabilities[i], options.confidence_factor);
    }
    const double cell = std::max(options.radius_m, 1e-6);
    Grid grid;
    for (std::size_t i = 0; i < n; ++i)
        if (r.confident[i]) grid[cell_of(positions[i], cell)].push_back(i);
    const double r2 = options.radius_m * options.radius_m;
    for (std::size_t i = 0; i < n; ++i) {
        if (r.confident[i]) continue;
        std::set<int> candidates;
        const auto [cx, cy] = cell_of(positions[i], cell);
        for (long dx = -1; dx <= 1; ++dx)
            for (long dy = -1; dy <= 1; ++dy) {
                const auto it = grid.find({cx + dx, cy + dy});
                if (it == grid.end()) continue;
                for (std::size_t j : it->second)
                    if (j != i && (positions[j] - positions[i]).squaredNorm() <= r2) candidates.insert(r.species[j]);
            }
        if (candidates.empty()) continue;
        int best = *candidates.begin();
        for (int c : candidates)
            if (probabilities[i][c] > probabilities[i][best]) best = c;  // ties: the lower class index
        r.changed[i] = best != r.species[i];
        r.species[i] = best;
    }
    return r;
}

}  // namespace treelobes::classify
