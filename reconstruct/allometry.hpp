// Allometric branch diameters of Livny et al. 2011, §4.1:
//   d(u)  = d_root * (l(u) / l(root))^gamma     (Eq. 1; l(u) = total edge length below u)
//   d'(u) = f_s * d(u)                           (Eq. 2; the lobe stage's confidence diameter)
// gamma and f_s come from the species library (config/species.yaml).
#pragma once

#include "core/tree_graph.hpp"

#include <vector>

namespace treelobes {

struct AllometryOptions {
    double gamma = 1.5;  // Livny et al. 2011: about 1.5 for many species (Table 1: 1.2..1.9)
    double fs = 1.0;     // Livny et al. 2011, Table 1: 0.8..0.986; 1.0 for trees without leaves
};

struct AllometricDiameters {
    std::vector<float> diameter;       // d(u) per node (metres)
    std::vector<float> lobe_diameter;  // d'(u) = f_s d(u) per node
};

// Sets every node's radius to d(u)/2 and returns d and d'. Throws Error(Usage) for a
// non-positive root diameter or gamma, or f_s outside (0, 1].
AllometricDiameters apply_allometry(TreeGraph& tree, double root_diameter, const AllometryOptions& options = {});

}  // namespace treelobes
