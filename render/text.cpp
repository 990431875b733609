#include "render/text.hpp"

#include <cctype>
#include <map>

namespace treelobes::render {

namespace {

// 3x5 glyphs, rows top to bottom.
const std::map<char, const char*>& glyphs() {
    static const std::map<char, const char*> g = {
            {'0', "111101101101111"}, {'1', "010110010010111"}, {'2', "111001111100111"}, {'3', "111001111001111"},
            {'4', "101101111001001"}, {'5', "111100111001111"}, {'6', "111100111101111"}, {'7', "111001001001001"},
            {'8', "111101111101111"}, {'9', "111101111001111"}, {'A', "010101111101101"}, {'B', "110101110101110"},
            {'C', "011100100100011"}, {'D', "110101101101110"}, {'E', "111100110100111"}, {'F', "111100110100100"},
            {'G', "011100101101011"}, {'H', "101101111101101"}, {'I', "111010010010111"}, {'J', "001001001101010"},
            {'K', "101101110101101"}, {'L', "100100100100111"}, {'M', "101111111101101"}, {'N', "110101101101101"},
            {'O', "010101101101010"}, {'P', "110101110100100"}, {'Q', "010101101110011"}, {'R', "110101110101101"},
            {'S', "011100010001110"}, {'T', "111010010010010"}, {'U', "101101101101111"}, {'V', "101101101101010"},
            {'W', "101101111111101"}, {'X', "101101010101101"}, {'Y', "101101010010010"}, {'Z', "111001010100111"},
            {'_', "000000000000111"}, {'.', "000000000000010"}, {'-', "000000111000000"}, {'%', "101001010100101"},
            {' ', "000000000000000"}, {'/', "001001010100100"}, {'(', "010100100100010"}, {')', "010001001001010"},
            {':', "000010000010000"}, {'=', "000111000111000"},
    };
    return g;
}

}  // namespace

void draw_text(Image& image, int x, int y, const std::string& text, int scale, Rgba colour) {
    for (char ch : text) {
        const auto it = glyphs().find(static_cast<char>(std::toupper(static_cast<unsigned char>(ch))));
        if (it != glyphs().end())
            for (int row = 0; row < 5; ++row)
                for (int col = 0; col < 3; ++col)
                    if (it->second[row * 3 + col] == '1')
                        image.fill_rect(x + col * scale, y + row * scale, x + (col + 1) * scale, y + (row + 1) * scale, colour);
        x += 4 * scale;
    }
}

int text_width(const std::string& text, int scale) { return static_cast<int>(text.size()) * 4 * scale; }

}  // namespace treelobes::render
