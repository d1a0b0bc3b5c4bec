// `softevo view ... --export-html out.html`: one self-contained HTML file that replays a
// session with no server and no network (a paper's supplementary material). It embeds three.js,
// the page, and the session's frames at `fps` frames per simulated second, packed small:
//
//   positions   int32 multiples of voxel_size / 128 (about 0.08 mm), each frame as the
//               difference to the frame before, byte planes split (all lowest bytes first, ...)
//   orientations int8 quaternion components x 127, differences to the frame before, wrapping
//   pressures, components, fitness, centroid, heading, target, time: float32, byte planes split
//   valves      uint8 openings x 255
//
// zlib-deflated (the page inflates with the browser's DecompressionStream("deflate")) and
// base64 in a <script> element. docs/viewer.md has the layout.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "view/client_session.hpp"
#include "view/session.hpp"

namespace softevo::view {

// The packed frames (before deflate) of every k-th record of a finished session, the last
// record always included.
std::string pack_frames(const Session& session, double fps);

// zlib format (RFC 1950), the "deflate" of the Compression Streams standard.
std::string deflate_zlib(const std::string& bytes);
std::string base64(const std::string& bytes);

// JSON text made safe to embed in HTML (inside <script>, or in an attribute) by one rule, not by
// matching tags: every '<', '>', '&' and the line separators U+2028/U+2029 written as \uXXXX.
// Valid JSON has these only inside strings, where \uXXXX means the same character, so the
// page's JSON.parse gives back exactly what was escaped; no robot name can end the element.
std::string json_for_html(std::string_view json);

// The page with everything embedded: the client's session simulated to its end, its hello and
// end note as the live page gets them. Throws std::runtime_error naming a missing page file.
std::string export_html(ClientSession& client, const std::string& web_dir, double fps);

}  // namespace softevo::view
