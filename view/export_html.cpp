// See export_html.hpp.
#include "view/export_html.hpp"

#include <zlib.h>

#include <cmath>
#include <cstring>
#include <stdexcept>

#include "view/bytes.hpp"
#include "view/server.hpp"

namespace softevo::view {

namespace {

constexpr std::uint32_t kPackMagic = 0x31585653;  // "SVX1"
constexpr double kQuantaPerVoxel = 128.0;

// Byte planes of 4-byte values: all first bytes, then all second bytes, ... (deflate finds the
// runs of equal high bytes of small differences).
template <class T>
void append_planes(std::string& out, const std::vector<T>& values) {
  static_assert(sizeof(T) == 4);
  const std::size_t n = values.size();
  const std::size_t start = out.size();
  out.resize(start + 4 * n);
  for (std::size_t i = 0; i < n; ++i) {
    unsigned char b[4];
    std::memcpy(b, &values[i], 4);
    for (int k = 0; k < 4; ++k) out[start + k * n + i] = static_cast<char>(b[k]);
  }
}

// Replaces the part of `page` between <!-- softevo:NAME --> and <!-- /softevo:NAME -->.
std::string replace_marked(std::string page, const std::string& name, const std::string& with) {
  const std::string open = "<!-- softevo:" + name + " -->",
                    close = "<!-- /softevo:" + name + " -->";
  const auto a = page.find(open), b = page.find(close);
  if (a == std::string::npos || b == std::string::npos || b < a)
    throw std::runtime_error("view/web/index.html: marker " + open + " missing");
  return page.replace(a, b + close.size() - a, with);
}

// Our own code (app.js) inside <script>: a "</script" in any letter case would end the element
// early. Written as "<\/script", which means the same inside a JavaScript string or regex.
std::string script_safe(std::string text) {
  const auto lower = [](char c) { return c >= 'A' && c <= 'Z' ? static_cast<char>(c + 32) : c; };
  for (std::size_t at = 0; at + 8 <= text.size(); ++at) {
    static constexpr char kClose[] = "</script";
    bool match = true;
    for (std::size_t k = 0; k < 8 && match; ++k) match = lower(text[at + k]) == kClose[k];
    if (match) text.replace(at, 2, "<\\/");
  }
  return text;
}

}  // namespace

std::string json_for_html(std::string_view json) {
  std::string out;
  out.reserve(json.size());
  for (std::size_t i = 0; i < json.size(); ++i) {
    const char c = json[i];
    if (c == '<') {
      out += "\\u003c";
    } else if (c == '>') {
      out += "\\u003e";
    } else if (c == '&') {
      out += "\\u0026";
    } else if (c == '\xE2' && i + 2 < json.size() && json[i + 1] == '\x80' &&
               (json[i + 2] == '\xA8' || json[i + 2] == '\xA9')) {
      out += json[i + 2] == '\xA8' ? "\\u2028" : "\\u2029";  // UTF-8 E2 80 A8 / E2 80 A9
      i += 2;
    } else {
      out += c;
    }
  }
  return out;
}

std::string base64(const std::string& bytes) {
  static constexpr char kAlphabet[] =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  std::size_t i = 0;
  for (; i + 2 < bytes.size(); i += 3) {
    const std::uint32_t v = (static_cast<unsigned char>(bytes[i]) << 16) |
                            (static_cast<unsigned char>(bytes[i + 1]) << 8) |
                            static_cast<unsigned char>(bytes[i + 2]);
    for (int k = 3; k >= 0; --k) out += kAlphabet[(v >> (6 * k)) & 63];
  }
  if (i < bytes.size()) {
    std::uint32_t v = static_cast<unsigned char>(bytes[i]) << 16;
    if (i + 1 < bytes.size()) v |= static_cast<unsigned char>(bytes[i + 1]) << 8;
    out += kAlphabet[(v >> 18) & 63];
    out += kAlphabet[(v >> 12) & 63];
    out += i + 1 < bytes.size() ? kAlphabet[(v >> 6) & 63] : '=';
    out += '=';
  }
  return out;
}

std::string deflate_zlib(const std::string& bytes) {
  uLongf size = compressBound(static_cast<uLong>(bytes.size()));
  std::string out(size, '\0');
  const int rc = compress2(reinterpret_cast<Bytef*>(out.data()), &size,
                           reinterpret_cast<const Bytef*>(bytes.data()),
                           static_cast<uLong>(bytes.size()), Z_BEST_COMPRESSION);
  if (rc != Z_OK) throw std::runtime_error("zlib compress2 failed (" + std::to_string(rc) + ")");
  out.resize(size);
  return out;
}

std::string pack_frames(const Session& session, double fps) {
  if (!(fps > 0.0)) throw std::invalid_argument("export fps must be > 0");
  const int every = std::max(1, static_cast<int>(std::lround(session.control_rate() / fps)));
  std::vector<int> chosen;
  for (int r = 0; r < session.records(); r += every) chosen.push_back(r);
  if (chosen.back() != session.records() - 1) chosen.push_back(session.records() - 1);
  const FrameRecord& first = session.record(0);
  const std::size_t items = first.positions.size() / 3;
  const std::size_t chambers = first.pressures_pa.size();
  const std::size_t components = first.components.size();
  const double quantum = session.input().body.voxel_size / kQuantaPerVoxel;  // [m]

  std::vector<std::int32_t> positions;
  std::string orientations;
  std::vector<float> time, pressures, components_so_far, fitness, cx, cy, heading, target;
  std::string valves;
  std::vector<std::int32_t> last_q(3 * items, 0);
  std::vector<std::int8_t> last_o(4 * items, 0);
  for (int r : chosen) {
    const FrameRecord& f = session.record(r);
    if (f.positions.size() != 3 * items) throw std::logic_error("records of different bodies");
    time.push_back(static_cast<float>(f.time));
    for (std::size_t i = 0; i < 3 * items; ++i) {
      const double q = std::nearbyint(f.positions[i] / quantum);
      const auto v = static_cast<std::int32_t>(std::clamp(q, -1.0e9, 1.0e9));
      positions.push_back(v - last_q[i]);  // no overflow: both within +-1e9
      last_q[i] = v;
    }
    for (std::size_t i = 0; i < 4 * items; ++i) {
      const auto o = static_cast<std::int8_t>(std::lround(f.orientations[i] / 32767.0 * 127.0));
      orientations +=
          static_cast<char>(static_cast<std::uint8_t>(o) - static_cast<std::uint8_t>(last_o[i]));
      last_o[i] = o;
    }
    for (std::size_t q = 0; q < chambers; ++q) {
      pressures.push_back(q < f.pressures_pa.size() ? f.pressures_pa[q] : 0.0f);
      for (int k = 0; k < 2; ++k) {
        const std::size_t v = 2 * q + k;
        const float u = v < f.valves.size() ? f.valves[v] : 0.0f;
        valves += static_cast<char>(std::lround(std::clamp(u, 0.0f, 1.0f) * 255.0f));
      }
    }
    for (std::size_t c = 0; c < components; ++c) components_so_far.push_back(f.components[c]);
    fitness.push_back(f.fitness);
    cx.push_back(f.centroid_x);
    cy.push_back(f.centroid_y);
    heading.push_back(f.heading_rad);
    target.push_back(f.target_deg);
  }
  std::string out;
  append_value(out, kPackMagic);
  append_value(out, static_cast<std::uint32_t>(chosen.size()));
  append_value(out, static_cast<std::uint32_t>(items));
  append_value(out, static_cast<std::uint16_t>(chambers));
  append_value(out, static_cast<std::uint16_t>(components));
  append_value(out, static_cast<float>(quantum));
  append_planes(out, time);
  append_planes(out, positions);
  out += orientations;
  append_planes(out, pressures);
  out += valves;
  append_planes(out, components_so_far);
  for (const auto* v : {&fitness, &cx, &cy, &heading, &target}) append_planes(out, *v);
  return out;
}

std::string export_html(ClientSession& client, const std::string& web_dir, double fps) {
  const std::string ended = client.run_to_end();
  const std::string packed = pack_frames(client.session(), fps);
  std::string page;
  std::string three, orbit, app, plots, style;
  for (auto& [url, file] : load_web_files(web_dir)) {
    if (url == "/") page = file.bytes;
    if (url == "/vendor/three.module.min.js") three = file.bytes;
    if (url == "/vendor/OrbitControls.js") orbit = file.bytes;
    if (url == "/app.js") app = file.bytes;
    if (url == "/plots.js") plots = file.bytes;
    if (url == "/style.css") style = file.bytes;
  }
  const auto data_url = [](const std::string& js) {
    return "data:text/javascript;base64," + base64(js);
  };
  const std::string head =
      "<script type=\"importmap\">{\"imports\":{\"three\":\"" + data_url(three) +
      "\",\"three/addons/controls/OrbitControls.js\":\"" + data_url(orbit) +
      "\",\"softevo/plots.js\":\"" + data_url(plots) + "\"}}</script>\n<style>\n" + style +
      "\n</style>\n<script type=\"application/json\" id=\"softevo-hello\">" +
      json_for_html(client.hello()) +
      "</script>\n<script type=\"application/json\" id=\"softevo-ended\">" + json_for_html(ended) +
      "</script>\n<script type=\"text/plain\" id=\"softevo-frames\">" +
      base64(deflate_zlib(packed)) + "</script>\n";
  page = replace_marked(page, "head", head);
  page =
      replace_marked(page, "app", "<script type=\"module\">\n" + script_safe(app) + "\n</script>");
  return page;
}

}  // namespace softevo::view
