// JointBoost model files (classify/jointboost.cpp): JSON structure, versions 1-3, routing,
// stumps and their references to classes and features. A model that loads must also predict:
// it is evaluated on one row of features (as `classify predict` does after the column check).
#include "classify/jointboost.hpp"
#include "fuzz_support.hpp"

#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const auto path = treelobes::fuzz::input_file(treelobes::fuzz::as_text(data, size), "json");
    treelobes::fuzz::expect_only_input_errors([&] {
        const treelobes::classify::JointBoostModel model = treelobes::classify::load_jointboost(path);
        const std::vector<double> features(model.feature_names.size(), 1.0);
        model.probabilities(features.data());
    });
    return 0;
}
