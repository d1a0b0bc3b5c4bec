// PNG files through libpng's simplified API (see png.hpp).
#include "render/png.hpp"

#ifdef SOFTEVO_HAVE_PNG
#include <png.h>
#endif

#include <cstring>
#include <stdexcept>

#include "common/safe_write.hpp"

namespace softevo::render {

void require_png_support([[maybe_unused]] const std::string& path) {
#ifndef SOFTEVO_HAVE_PNG
  throw std::runtime_error("cannot write or read PNG " + path +
                           ": softevo was built without libpng (install libpng-dev, reconfigure "
                           "and rebuild; video output such as .mp4 works without it)");
#endif
}

#ifdef SOFTEVO_HAVE_PNG
void write_png(const Image& image, const std::string& path, Overwrite overwrite) {
  if (image.width <= 0 || image.height <= 0 ||
      image.rgb.size() != static_cast<std::size_t>(image.width) * image.height * 3) {
    throw std::invalid_argument("write_png " + path + ": image has no pixels");
  }
  png_image out;
  std::memset(&out, 0, sizeof(out));
  out.version = PNG_IMAGE_VERSION;
  out.width = static_cast<png_uint_32>(image.width);
  out.height = static_cast<png_uint_32>(image.height);
  out.format = PNG_FORMAT_RGB;
  // Atomic, and never through a symlink or over a special file (docs/output-files.md).
  AtomicOutput file(path, overwrite);
  if (png_image_write_to_file(&out, file.temp_path().c_str(), 0, image.rgb.data(), 0, nullptr) ==
      0) {
    const std::string reason = out.message;
    png_image_free(&out);
    throw std::runtime_error("cannot write PNG " + path + ": " + reason);
  }
  file.commit();
}

Image read_png(const std::string& path) {
  png_image in;
  std::memset(&in, 0, sizeof(in));
  in.version = PNG_IMAGE_VERSION;
  if (png_image_begin_read_from_file(&in, path.c_str()) == 0) {
    throw std::runtime_error("cannot read PNG " + path + ": " + in.message);
  }
  in.format = PNG_FORMAT_RGB;
  Image image(static_cast<int>(in.width), static_cast<int>(in.height), {0, 0, 0});
  if (png_image_finish_read(&in, nullptr, image.rgb.data(), 0, nullptr) == 0) {
    const std::string reason = in.message;
    png_image_free(&in);
    throw std::runtime_error("cannot read PNG " + path + ": " + reason);
  }
  return image;
}
#else
void write_png(const Image&, const std::string& path, Overwrite) {
  require_png_support(path);
}

Image read_png(const std::string& path) {
  require_png_support(path);
  return {};
}
#endif

}  // namespace softevo::render
