// Animated PNG (APNG 1.0, the Mozilla extension of PNG): the frames of an orbit preview in one
// file that browsers and image viewers play, and that plain PNG readers show as its first frame.
#pragma once

#include "render/image.hpp"

#include <filesystem>
#include <string>
#include <vector>

namespace treelobes::render {

// The APNG bytes of `frames` (all the same size, at least one), each shown `delay_ms`
// milliseconds, looping forever. Frame 0 is the default image (its data in IDAT), so a reader
// without APNG support shows it.
std::string encode_apng(const std::vector<Image>& frames, int delay_ms);
// Writes encode_apng's bytes atomically.
void write_apng(const std::vector<Image>& frames, int delay_ms, const std::filesystem::path& path);

}  // namespace treelobes::render
