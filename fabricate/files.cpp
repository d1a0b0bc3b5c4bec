// STL, slice and mold files of a fabrication (fabricate.hpp, docs/fabrication.md).
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>

#include <nlohmann/json.hpp>

#include "fabricate/fabricate.hpp"
#include "render/png.hpp"
#include "render/render.hpp"

namespace softevo::fabricate {

namespace {

namespace fs = std::filesystem;

void put_u32(std::string& out, std::uint32_t v) {
  char b[4];
  std::memcpy(b, &v, 4);  // STL is little-endian, as every supported target (docs/guide.md)
  out.append(b, 4);
}
void put_f32(std::string& out, double v) {
  const float f = static_cast<float>(v);
  char b[4];
  std::memcpy(b, &f, 4);
  out.append(b, 4);
}

// Writes every (path, bytes) pair atomically, after checking every target first, so that a
// refused target leaves nothing behind.
void write_all(const std::vector<std::pair<std::string, std::string>>& files, Overwrite overwrite) {
  for (const auto& [path, bytes] : files) check_output_target(path, overwrite);
  std::vector<std::unique_ptr<AtomicOutput>> outputs;
  for (const auto& [path, bytes] : files) {
    outputs.push_back(std::make_unique<AtomicOutput>(path, overwrite));
    std::FILE* f = std::fopen(outputs.back()->temp_path().c_str(), "wb");
    const bool ok = f && std::fwrite(bytes.data(), 1, bytes.size(), f) == bytes.size();
    if (f && std::fclose(f) != 0) throw OutputFileError(path + ": cannot write");
    if (!ok) throw OutputFileError(path + ": cannot write");
  }
  for (auto& out : outputs) out->commit();
}

}  // namespace

void make_output_directory(const std::string& dir, const char* option) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec || !fs::is_directory(dir))
    throw FabricateError(std::string("fabricate: ") + option + " " + dir +
                         ": cannot create the directory" + (ec ? ": " + ec.message() : ""));
}

std::vector<std::string> stl_paths(const Fabrication& fab, const std::string& out) {
  std::string stem = out;
  std::string ext = stem.size() > 4 ? stem.substr(stem.size() - 4) : "";
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (ext == ".stl") stem.resize(stem.size() - 4);
  std::vector<std::string> paths;
  for (const MaterialGroup& g : fab.groups) paths.push_back(stem + "-" + g.name + ".stl");
  return paths;
}

SliceSize slice_size(const Fabrication& fab) {
  const Options& o = fab.options;
  const Grid& g = fab.grid;
  SliceSize size;
  size.pixel_x = 0.0254 / o.dpi_x;
  size.pixel_y = 0.0254 / o.dpi_y;
  // Pixels to cover the body; a quotient a rounding error above a whole number (0.07 m / 2.5 mm
  // = 28.000000000000004) is that number, not one more.
  const auto count = [](double length, double pitch) { return std::ceil(length / pitch - 1e-9); };
  const double w = count(g.planes[0].back(), size.pixel_x),
               h = count(g.planes[1].back(), size.pixel_y), l = count(g.planes[2].back(), o.layer);
  // The figures as a person typed or would count them: 15 significant digits turn the 30 um
  // that went through metres (30.000000000000004) back into 30, and keep whole counts whole.
  const auto figure = [](double v) {
    char text[32];
    std::snprintf(text, sizeof text, "%.15g", v);
    return std::string(text);
  };
  if (w * h * l > static_cast<double>(o.max_pixels) || w > 1e6 || h > 1e6)
    throw FabricateError("fabricate: --slices at --dpi " + figure(o.dpi_x) + "," + figure(o.dpi_y) +
                         " and --layer-um " + figure(o.layer * 1e6) + " would be " + figure(w) +
                         " x " + figure(h) + " x " + figure(l) + " pixels, more than " +
                         std::to_string(o.max_pixels) +
                         " (the stated limit): lower --dpi or raise --layer-um");
  size.width = static_cast<int>(w);
  size.height = static_cast<int>(h);
  size.layers = static_cast<int>(l);
  return size;
}

std::vector<std::string> slice_paths(const Fabrication& fab, const std::string& dir) {
  std::vector<std::string> paths;
  const int layers = slice_size(fab).layers;
  for (int z = 0; z < layers; ++z) {
    char name[32];
    std::snprintf(name, sizeof name, "slice-%05d.png", z);
    paths.push_back((fs::path(dir) / name).string());
  }
  paths.push_back((fs::path(dir) / "palette.json").string());
  return paths;
}

std::vector<std::string> mold_paths(const Mold& mold, const std::string& dir) {
  std::vector<std::string> paths;
  for (const auto* list : {&mold.parts, &mold.cores}) {
    for (const Mesh& m : *list) paths.push_back((fs::path(dir) / (m.name + ".stl")).string());
  }
  paths.push_back((fs::path(dir) / "mold.json").string());
  return paths;
}

std::string stl_bytes(const Mesh& mesh) {
  std::string out;
  out.reserve(84 + 50 * mesh.triangles.size());
  std::string header = "softevo " + mesh.name + " (mm)";
  header.resize(80, ' ');
  out += header;
  put_u32(out, static_cast<std::uint32_t>(mesh.triangles.size()));
  for (const auto& t : mesh.triangles) {
    const Eigen::Vector3d a = mesh.vertices[t[0]] * 1e3, b = mesh.vertices[t[1]] * 1e3,
                          c = mesh.vertices[t[2]] * 1e3;
    const Eigen::Vector3d normal = (b - a).cross(c - a).normalized();
    for (const Eigen::Vector3d& v : {normal, a, b, c}) {
      put_f32(out, v.x());
      put_f32(out, v.y());
      put_f32(out, v.z());
    }
    out.append(2, '\0');
  }
  return out;
}

std::vector<std::string> write_stls(const Fabrication& fab, const std::string& out,
                                    Overwrite overwrite) {
  const std::vector<std::string> paths = stl_paths(fab, out);
  std::vector<std::pair<std::string, std::string>> files;
  for (std::size_t g = 0; g < paths.size(); ++g)
    files.emplace_back(paths[g], stl_bytes(fab.groups[g].mesh));
  write_all(files, overwrite);
  return paths;
}

int write_slices(const Fabrication& fab, const std::string& dir, Overwrite overwrite) {
  render::require_png_support(dir + "/slice-00000.png");
  const Options& o = fab.options;
  const Grid& g = fab.grid;
  const SliceSize size = slice_size(fab);
  const int W = size.width, H = size.height, L = size.layers;
  const double px = size.pixel_x, py = size.pixel_y;
  // Palette: pixel value = grid label (materials 1..10, cavities 100 + q, channels 200 + q, voids
  // 250), so a pixel names what is printed there.
  nlohmann::ordered_json palette;
  palette["format"] = "softevo.slices/1";
  palette["width"] = W;
  palette["height"] = H;
  palette["layers"] = L;
  palette["pixel_mm"] = {px * 1e3, py * 1e3};
  palette["layer_mm"] = o.layer * 1e3;
  palette["orientation"] = "column = x, row = y (row 0 at y = 0), slice n at z = (n + 0.5) layer";
  auto& values = palette["values"];
  values["0"] = {{"kind", "empty"}};
  for (const MaterialGroup& grp : fab.groups) {
    char colour[8];
    std::snprintf(colour, sizeof colour, "#%02x%02x%02x", grp.colour[0], grp.colour[1],
                  grp.colour[2]);
    values[std::to_string(grp.material)] = {{"kind", "material"},
                                            {"group", grp.name},
                                            {"youngs_modulus_pa", grp.youngs_modulus},
                                            {"colour", colour}};
  }
  for (const Inlet& in : fab.inlets) {
    values[std::to_string(label::kCavity + in.chamber)] = {
        {"kind", "cavity"}, {"chamber", in.chamber}, {"fill", "support"}};
    values[std::to_string(label::kChannel + in.chamber)] = {
        {"kind", "channel"}, {"chamber", in.chamber}, {"fill", "support"}};
  }
  if (fab.void_cells > 0)
    values[std::to_string(label::kVoid)] = {{"kind", "void"}, {"fill", "support"}};

  const std::vector<std::string> names = slice_paths(fab, dir);
  make_output_directory(dir, "--slices");
  for (const auto& name : names) check_output_target(name, overwrite);
  const std::string& palette_path = names.back();
  // The grid cell of every column and row once; a slice is then a table lookup per pixel.
  std::vector<int> cx(W), cy(H);
  for (int x = 0; x < W; ++x) cx[x] = g.axis_cell(0, (x + 0.5) * px);
  for (int y = 0; y < H; ++y) cy[y] = g.axis_cell(1, (y + 0.5) * py);
  render::Image image(W, H, {0, 0, 0});
  for (int z = 0; z < L; ++z) {
    const int cz = g.axis_cell(2, (z + 0.5) * o.layer);
    for (int y = 0; y < H; ++y) {
      for (int x = 0; x < W; ++x) {
        const int v = cx[x] < 0 || cy[y] < 0 || cz < 0 ? 0 : g.at(cx[x], cy[y], cz);
        const auto b = static_cast<std::uint8_t>(v);
        image.set(x, y, {b, b, b});
      }
    }
    render::write_png(image, names[z], overwrite);
  }
  write_all({{palette_path, palette.dump(2) + "\n"}}, overwrite);
  return L;
}

std::vector<std::string> write_mold(const Mold& mold, const std::string& dir, Overwrite overwrite) {
  make_output_directory(dir, "--mold");
  const std::vector<std::string> paths = mold_paths(mold, dir);
  std::vector<std::pair<std::string, std::string>> files;
  std::size_t k = 0;
  for (const auto* list : {&mold.parts, &mold.cores}) {
    for (const Mesh& m : *list) files.emplace_back(paths[k++], stl_bytes(m));
  }
  files.emplace_back(paths.back(), mold.json());
  write_all(files, overwrite);
  return paths;
}

}  // namespace softevo::fabricate
