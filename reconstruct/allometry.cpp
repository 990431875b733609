#include "reconstruct/allometry.hpp"

#include "core/error.hpp"

#include <cmath>
#include <string>

namespace treelobes {

AllometricDiameters apply_allometry(TreeGraph& tree, double root_diameter, const AllometryOptions& o) {
    if (!(root_diameter > 0) || !std::isfinite(root_diameter))
        throw Error::usage("allometry: the root diameter must be > 0, got " + std::to_string(root_diameter));
    if (!(o.gamma > 0) || !std::isfinite(o.gamma)) throw Error::usage("allometry: gamma must be > 0");
    if (!(o.fs > 0 && o.fs <= 1)) throw Error::usage("allometry: f_s must be in (0, 1]");
    AllometricDiameters out;
    if (tree.empty()) return out;
    const std::vector<float> length = tree.subtree_lengths();
    const double total = length[0];
    out.diameter.resize(tree.size());
    out.lobe_diameter.resize(tree.size());
    for (std::size_t u = 0; u < tree.size(); ++u) {
        // A single-node tree has l(root) = 0: it keeps the root diameter.
        const double ratio = total > 0 ? static_cast<double>(length[u]) / total : 1.0;
        const double d = root_diameter * std::pow(ratio, o.gamma);
        out.diameter[u] = static_cast<float>(d);
        out.lobe_diameter[u] = static_cast<float>(o.fs * d);
        tree.nodes[u].radius = static_cast<float>(0.5 * d);
    }
    return out;
}

}  // namespace treelobes
