// PNG files of rendered images (libpng, optional: SOFTEVO_ENABLE_PNG). Written atomically
// (common/safe_write.hpp: an existing regular file is replaced only with Overwrite::replace,
// never through a symlink or over a special file, docs/output-files.md).
#pragma once

#include <string>

#include "common/safe_write.hpp"
#include "render/render.hpp"

namespace softevo::render {

// Throws std::runtime_error naming the path and the reason.
void write_png(const Image& image, const std::string& path,
               Overwrite overwrite = Overwrite::refuse);
Image read_png(const std::string& path);
// libpng is optional (SOFTEVO_ENABLE_PNG): throws std::runtime_error naming `path` when this
// build has no PNG support, so a render fails before it simulates.
void require_png_support(const std::string& path);

}  // namespace softevo::render
