#include "core/asprs_classes.hpp"

#include <array>
#include <string_view>

namespace treelobes {

namespace {

// LAS 1.4 R15, Table 17, codes 0-22; empty where the code is reserved.
constexpr std::array<std::string_view, 23> kNames{"never classified",
                                                  "unclassified",
                                                  "ground",
                                                  "low vegetation",
                                                  "medium vegetation",
                                                  "high vegetation",
                                                  "building",
                                                  "low noise",
                                                  "",
                                                  "water",
                                                  "rail",
                                                  "road surface",
                                                  "",
                                                  "wire guard",
                                                  "wire conductor",
                                                  "transmission tower",
                                                  "wire-structure connector",
                                                  "bridge deck",
                                                  "high noise",
                                                  "overhead structure",
                                                  "ignored ground",
                                                  "snow",
                                                  "temporal exclusion"};

}  // namespace

bool asprs_never_a_tree(std::uint8_t code) {
    return code == 6 || code == 7 || code == 9 || code == 10 || code == 11 || (code >= 13 && code <= 22);
}

std::string asprs_class_name(std::uint8_t code) {
    if (code < kNames.size() && !kNames[code].empty()) return std::string(kNames[code]);
    return "class " + std::to_string(code);
}

}  // namespace treelobes
