// Text in a TrueType font: Debian's DejaVu Sans (fonts-dejavu-core) rasterised by stb_truetype
// (libstb-dev), anti-aliased, with lower case. Without either at build time, or the font file
// at run time, draw_text (render.hpp) keeps its built-in 5x7 bitmap font.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>

#include "render/render.hpp"

namespace softevo::render {

// Draws `text` with its top-left corner at pixel (x, y), cap height about 7 `size` pixels (the
// bitmap font's), blended over the image. Returns false, drawing nothing, when no TrueType font
// is available. The font file is the one found at build time (SOFTEVO_FONT_FILE), or the one
// the environment variable SOFTEVO_FONT names.
bool draw_font_text(Image& image, int x, int y, const std::string& text,
                    std::array<std::uint8_t, 3> colour, int size);
// Width [pixel] draw_font_text gives `text`; nullopt without a TrueType font.
std::optional<int> font_text_width(const std::string& text, int size);

}  // namespace softevo::render
