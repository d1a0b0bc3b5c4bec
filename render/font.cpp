#include "render/font.hpp"

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <vector>

#ifdef SOFTEVO_HAVE_STB_TRUETYPE
#define STB_TRUETYPE_IMPLEMENTATION
#define STBTT_STATIC
#include <stb/stb_truetype.h>
#endif

namespace softevo::render {

#ifdef SOFTEVO_HAVE_STB_TRUETYPE
namespace {

struct Font {
  std::vector<unsigned char> data;
  stbtt_fontinfo info{};
  bool loaded = false;
};

Font load_font() {
  Font font;
  const char* chosen = std::getenv("SOFTEVO_FONT");
  const std::string path = chosen != nullptr && *chosen != '\0' ? chosen : SOFTEVO_FONT_FILE;
  std::ifstream in(path, std::ios::binary);
  if (!in) return font;
  font.data.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  const int offset = stbtt_GetFontOffsetForIndex(font.data.data(), 0);
  font.loaded = offset >= 0 && stbtt_InitFont(&font.info, font.data.data(), offset) != 0;
  return font;
}

// Read once per process; the renderer is single-threaded per image but a Font is only read.
const Font& font() {
  static const Font loaded = load_font();
  return loaded;
}

}  // namespace

bool draw_font_text(Image& image, int x, int y, const std::string& text,
                    std::array<std::uint8_t, 3> colour, int size) {
  const Font& f = font();
  if (!f.loaded) return false;
  // DejaVu's cap height is 0.73 of its em: an em of 9.6 `size` pixels gives the 7 of the bitmap.
  const float scale = stbtt_ScaleForMappingEmToPixels(&f.info, 9.6F * static_cast<float>(size));
  int ascent = 0, descent = 0, line_gap = 0;
  stbtt_GetFontVMetrics(&f.info, &ascent, &descent, &line_gap);
  // The bitmap font's top row is the cap line: put the cap line at y.
  const int baseline = y + static_cast<int>(std::lround(7.0F * static_cast<float>(size)));
  float pen = static_cast<float>(x);
  std::vector<unsigned char> coverage;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const int codepoint = static_cast<unsigned char>(text[i]);
    int advance = 0, bearing = 0;
    stbtt_GetCodepointHMetrics(&f.info, codepoint, &advance, &bearing);
    const float shift = pen - std::floor(pen);
    int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
    stbtt_GetCodepointBitmapBoxSubpixel(&f.info, codepoint, scale, scale, shift, 0.0F, &x0, &y0,
                                        &x1, &y1);
    const int w = x1 - x0, h = y1 - y0;
    if (w > 0 && h > 0) {
      coverage.assign(static_cast<std::size_t>(w) * static_cast<std::size_t>(h), 0);
      stbtt_MakeCodepointBitmapSubpixel(&f.info, coverage.data(), w, h, w, scale, scale, shift,
                                        0.0F, codepoint);
      const int left = static_cast<int>(std::floor(pen)) + x0;
      for (int row = 0; row < h; ++row) {
        for (int col = 0; col < w; ++col) {
          const int px = left + col, py = baseline + y0 + row;
          if (px < 0 || py < 0 || px >= image.width || py >= image.height) continue;
          const float a = coverage[static_cast<std::size_t>(row * w + col)] / 255.0F;
          if (a <= 0.0F) continue;
          const std::array<std::uint8_t, 3> under = image.pixel(px, py);
          std::array<std::uint8_t, 3> mixed{};
          for (int c = 0; c < 3; ++c)
            mixed[c] =
                static_cast<std::uint8_t>(std::lround(under[c] + a * (colour[c] - under[c])));
          image.set(px, py, mixed);
        }
      }
    }
    pen += scale * static_cast<float>(advance);
    if (i + 1 < text.size())
      pen += scale * static_cast<float>(stbtt_GetCodepointKernAdvance(
                         &f.info, codepoint, static_cast<unsigned char>(text[i + 1])));
  }
  return true;
}
std::optional<int> font_text_width(const std::string& text, int size) {
  const Font& f = font();
  if (!f.loaded) return std::nullopt;
  const float scale = stbtt_ScaleForMappingEmToPixels(&f.info, 9.6F * static_cast<float>(size));
  float pen = 0.0F;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const int codepoint = static_cast<unsigned char>(text[i]);
    int advance = 0, bearing = 0;
    stbtt_GetCodepointHMetrics(&f.info, codepoint, &advance, &bearing);
    pen += scale * static_cast<float>(advance);
    if (i + 1 < text.size())
      pen += scale * static_cast<float>(stbtt_GetCodepointKernAdvance(
                         &f.info, codepoint, static_cast<unsigned char>(text[i + 1])));
  }
  return static_cast<int>(std::ceil(pen));
}
#else
bool draw_font_text(Image&, int, int, const std::string&, std::array<std::uint8_t, 3>, int) {
  return false;
}
std::optional<int> font_text_width(const std::string&, int) {
  return std::nullopt;
}
#endif

}  // namespace softevo::render
