#pragma once
// A compact 5x7 bitmap font (printable ASCII subset: digits, upper and lower case letters and
// the punctuation plots need), so plots can carry text without a font library.

#include <array>
#include <cstdint>

namespace mmlio::eval {

constexpr int kGlyphWidth = 5;
constexpr int kGlyphHeight = 7;
constexpr int kGlyphAdvance = 6;  // glyph width plus one column of spacing

/// Rows top to bottom; bit 4 of each row is the leftmost column. Characters without a glyph
/// get a hollow box so missing ones are visible rather than silently dropped.
const std::array<std::uint8_t, kGlyphHeight>& glyph(char c);

/// Rows the glyph is shifted down (descenders of g p q y hang below the baseline).
int glyphDrop(char c);

/// Whether `c` has its own glyph.
bool hasGlyph(char c);

}  // namespace mmlio::eval
