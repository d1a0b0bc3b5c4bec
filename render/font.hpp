// Text in pictures: draw_text and text_width draw in a TrueType font, Debian's DejaVu Sans
// (fonts-dejavu-core) rasterised by stb_truetype (libstb-dev), anti-aliased, with lower case
// (font.cpp). Without either at build time, or the font file at run time, they draw in the
// built-in 5x7 bitmap font (bitmap_font.cpp).
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>

#include "render/render.hpp"

namespace softevo::render {

// Text with its top-left corner at pixel (x, y), cap height 7 `size` pixels: in DejaVu Sans
// when the build has stb_truetype and the font (draw_font_text), else in a small built-in
// bitmap font (5x7 cells, printable ASCII in capitals; unknown characters are blanks, each font
// pixel `size` x `size` image pixels).
void draw_text(Image& image, int x, int y, const std::string& text,
               std::array<std::uint8_t, 3> colour, int size = 2);
// Width [pixel] of `text` as draw_text draws it.
int text_width(const std::string& text, int size = 2);

// Draws `text` with its top-left corner at pixel (x, y), cap height about 7 `size` pixels (the
// bitmap font's), blended over the image. Returns false, drawing nothing, when no TrueType font
// is available. The font file is the one found at build time (SOFTEVO_FONT_FILE), or the one
// the environment variable SOFTEVO_FONT names.
bool draw_font_text(Image& image, int x, int y, const std::string& text,
                    std::array<std::uint8_t, 3> colour, int size);
// Width [pixel] draw_font_text gives `text`; nullopt without a TrueType font.
std::optional<int> font_text_width(const std::string& text, int size);

}  // namespace softevo::render
