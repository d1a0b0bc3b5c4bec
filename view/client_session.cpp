// See client_session.hpp.
#include "view/client_session.hpp"

#include <algorithm>
#include <chrono>
#include <cstring>
#include <filesystem>

#include <nlohmann/json.hpp>

#include "fabricate/fabricate.hpp"
#include "view/bytes.hpp"
#include "view/export_html.hpp"

namespace softevo::view {

namespace {

using nlohmann::json;
namespace fs = std::filesystem;

Outgoing text(std::string s) {
  return {false, std::move(s)};
}

// A file name from a robot name: letters, digits, '-' and '_' only.
std::string file_stem(const std::string& name) {
  std::string s;
  for (char c : name) {
    const bool keep = std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_';
    s += keep ? c : '_';
  }
  return s.empty() ? "robot" : s.substr(0, 80);
}

// What the page is told of a failed save: the kind of failure in plain words, never the error's
// own text, which may hold temporary paths, the process id, file descriptors and addresses
// (libhdf5's error stack does; docs/viewer.md "Limits"). The whole text goes to the server's log.
std::string plain_save_failure(const std::string& detail) {
  static const std::pair<const char*, const char*> kReasons[] = {
      {"No space left on device", "no space is left on the disk"},
      {"Disk quota exceeded", "the disk quota is exceeded"},
      {"Read-only file system", "the save directory is on a read-only file system"},
      {"Permission denied", "the save directory may not be written"},
      {"No such file or directory", "the save directory does not exist"},
      {"Not a directory", "the save directory does not exist"},
  };
  for (const auto& [cause, words] : kReasons)
    if (detail.find(cause) != std::string::npos)
      return std::string("the save failed: ") + words + "; nothing was written";
  return "the save failed; nothing was written (the server's log says why)";
}

// The ground's grid as the page reads it: float32 heights little-endian in base64.
json terrain_json(const TerrainGrid& g) {
  std::string bytes(g.z.size() * sizeof(float), '\0');
  std::memcpy(bytes.data(), g.z.data(), bytes.size());
  return {{"kind", g.kind}, {"x0", g.x0}, {"y0", g.y0},        {"step", g.step},
          {"nx", g.nx},     {"ny", g.ny}, {"z", base64(bytes)}};
}

// The fabrication geometry the page's "fabrication" box shows (docs/fabrication.md): each
// chamber's inlet channel as one box per wall voxel it passes through, in that voxel's frame
// (centre relative to the voxel's centre, size [m]), so that it moves with the voxel. A body
// fabricate refuses gets {"error": message} instead.
json fabrication_json(const scene::Body& body) {
  json j;
  try {
    fabricate::Options inlets_only;
    inlets_only.meshes = false;
    const fabricate::Fabrication fab = fabricate::fabricate(body, {}, inlets_only);
    json channels = json::array();
    for (const fabricate::ChannelPiece& p : fabricate::channel_pieces(fab, body)) {
      channels.push_back({{"chamber", p.chamber},
                          {"voxel", p.voxel},
                          {"centre", {p.centre.x(), p.centre.y(), p.centre.z()}},
                          {"size", {p.size.x(), p.size.y(), p.size.z()}}});
    }
    j["channels"] = channels;
    j["channel_diameter"] = fab.options.channel_diameter;
  } catch (const fabricate::FabricateError& e) {
    j["error"] = e.what();
  }
  return j;
}

}  // namespace

ClientSession::ClientSession(const ViewInput& input, ClientOptions options)
    : input_(input), options_(std::move(options)), session_(std::make_unique<Session>(input)) {}

std::string ClientSession::hello() const {
  return hello_json(terrain_grid(*session_, options_.terrain_margin_m)).dump();
}

json ClientSession::hello_json(const TerrainGrid& ground) const {
  const scene::Body& body = input_.body;
  json j;
  j["type"] = "hello";
  j["name"] = input_.name;
  j["kind"] = to_string(input_.kind);
  j["live"] = session_->live();
  j["directed"] = session_->steerable();
  j["voxel_size"] = body.voxel_size;
  j["voxels"] = body.voxel_cells.size();
  j["chamber_cells"] = body.chamber_cells.size();
  j["chambers"] = body.chamber_count;
  json colours = json::array();
  for (int m : body.voxel_material) {
    const auto c = render::material_colour(m, body.material_count);
    colours.push_back({c[0], c[1], c[2]});
  }
  j["voxel_colours"] = colours;
  // The lattice cells (i, j, k) of the voxels, then of the chamber cells, flat: the page draws
  // the body deformed from them as the still renderer does (docs/rendering.md "Deformed
  // voxels"): which faces are skin, which corners neighbours share.
  json cells = json::array();
  for (const auto* list : {&body.voxel_cells, &body.chamber_cells})
    for (const auto& c : *list) cells.insert(cells.end(), {c.x(), c.y(), c.z()});
  j["cells"] = cells;
  j["chamber_index"] = body.chamber_index;
  j["fabrication"] = fabrication_json(body);
  j["planned_records"] = session_->planned_records();
  j["control_rate"] = session_->control_rate();
  j["component_names"] = session_->component_names();
  j["component_units"] = session_->component_units();
  j["fitness_unit"] = session_->fitness_unit();
  j["direction_deg"] = session_->steerable() && !input_.config.task.directions.empty()
                           ? json(input_.config.task.directions[0])
                           : json(nullptr);
  j["task"] = to_string(input_.config.task.kind);
  // The ground when it is not the flat floor: heights sampled here from physics/terrain (the
  // page draws them, it never computes a height itself) under the path so far.
  if (ground.nx > 0) j["terrain"] = terrain_json(ground);
  if (input_.archived) {
    const auto& a = *input_.archived;
    json arch{
        {"generation", a.generation}, {"id", a.id}, {"fitness", a.fitness}, {"units", a.units}};
    // The first unit's own fitness (the session simulates unit 0).
    const auto col = std::find(a.component_columns.begin(), a.component_columns.end(), "fitness");
    if (col != a.component_columns.end() && !a.components.empty())
      arch["unit_fitness"] =
          a.components[static_cast<std::size_t>(col - a.component_columns.begin())];
    j["archived"] = arch;
  }
  if (input_.trace_fitness) j["trace_fitness"] = *input_.trace_fitness;
  return j;
}

std::string ClientSession::state_json() const {
  return json{{"type", "state"},
              {"playing", playing_},
              {"speed", speed_},
              {"records", session_->records()},
              {"steering", session_->steering_log().size()}}
      .dump();
}

std::vector<Outgoing> ClientSession::start() {
  std::vector<Outgoing> out;
  ground_sent_ = terrain_grid(*session_, options_.terrain_margin_m);
  out.push_back(text(hello_json(ground_sent_).dump()));
  ground_sent_.z = {};
  out.push_back(text(state_json()));
  show(0, out);
  return out;
}

void ClientSession::show(int record, std::vector<Outgoing>& out) {
  record = std::clamp(record, 0, session_->records() - 1);
  if (record == shown_) return;
  shown_ = record;
  const bool last = session_->finished() && record == session_->records() - 1;
  out.push_back({true, encode_frame(session_->record(record), last)});
  // A robot near the edge of the page's ground gets the ground under its path so far.
  if (ground_sent_.nx == 0) return;
  if (auto ground = terrain_update(*session_, ground_sent_, record, options_.terrain_margin_m)) {
    out.push_back(text(json{{"type", "terrain"}, {"terrain", terrain_json(*ground)}}.dump()));
    ground_sent_ = std::move(*ground);
    ground_sent_.z = {};
  }
}

std::string ClientSession::run_to_end() {
  while (session_->advance()) {
  }
  return ended_json();
}

void ClientSession::note_end(std::vector<Outgoing>& out) {
  if (end_noted_ || !session_->finished()) return;
  end_noted_ = true;
  out.push_back(text(ended_json()));
}

std::string ClientSession::ended_json() const {
  json j{{"type", "ended"},
         {"status", softevo::to_string(session_->status())},
         {"message", session_->status_message()},
         {"time", session_->record(session_->records() - 1).time}};
  if (const auto& r = session_->result()) {
    j["fitness"] = r->fitness;
    j["components"] = r->components.empty() ? json::array() : json(r->components[0].values);
  } else if (input_.trace_fitness) {
    j["fitness"] = *input_.trace_fitness;
  }
  if (input_.archived) j["archived_fitness"] = input_.archived->fitness;
  return j.dump();
}

std::vector<Outgoing> ClientSession::handle(std::string_view message, bool is_text) {
  try {
    return act(parse_client_message(message, is_text));
  } catch (const ProtocolError& e) {
    return {text(error_json(e.what()))};
  } catch (const std::logic_error& e) {  // steering a gait robot, saving too early, ...
    return {text(error_json(e.what()))};
  } catch (const std::runtime_error& e) {  // a save that could not be written
    return {text(error_json(e.what()))};
  }
}

std::vector<Outgoing> ClientSession::act(const ClientMessage& m) {
  std::vector<Outgoing> out;
  switch (m.type) {
    case MessageType::play:
      playing_ = true;
      if (shown_ == session_->records() - 1 && session_->finished()) {
        shown_ = -1;  // at the end: play again from the start
        play_time_ = 0.0;
        show(0, out);
      }
      break;
    case MessageType::pause:
      playing_ = false;
      break;
    case MessageType::step:
      playing_ = false;
      if (shown_ + 1 >= session_->records()) session_->advance();
      show(shown_ + 1, out);
      play_time_ = session_->record(shown_).time;
      note_end(out);
      break;
    case MessageType::reset:
      session_ = std::make_unique<Session>(input_);
      saved_ = false;
      shown_ = -1;
      play_time_ = 0.0;
      end_noted_ = false;
      show(0, out);
      break;
    case MessageType::speed:
      speed_ = m.value;
      break;
    case MessageType::seek: {
      // Beyond the records there are: a live session simulates up to there (bounded by tick's
      // budget: the rest comes as playback goes on).
      const int target =
          static_cast<int>(std::min<std::int64_t>(m.frame, session_->planned_records() - 1));
      const auto t0 = std::chrono::steady_clock::now();
      while (target >= session_->records() && session_->advance() &&
             std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() <
                 options_.max_simulation_seconds_per_tick * 10) {
      }
      show(target, out);
      play_time_ = session_->record(shown_).time;
      note_end(out);
      break;
    }
    case MessageType::steer:
      // From the next frame simulated on, wherever the scrubber is: the log is in control
      // frames of the simulation, not of what is shown.
      session_->steer(m.value);
      break;
    case MessageType::save: {
      if (!session_->live()) throw std::logic_error("a trace is already saved");
      if (!session_->finished())
        throw std::logic_error("the session is saved when its simulation has ended");
      // Bounded, so that a page cannot fill the disk: each save writes a whole trace.
      if (saved_) throw std::logic_error("this session is saved already (reset to save another)");
      if (saves_ >= options_.max_saves)
        throw std::logic_error("at most " + std::to_string(options_.max_saves) + " saves per page");
      const auto now = std::chrono::steady_clock::now();
      if (last_save_ && std::chrono::duration<double>(now - *last_save_).count() <
                            options_.min_save_interval_seconds)
        throw std::logic_error("one save per " + json(options_.min_save_interval_seconds).dump() +
                               " s; try again in a moment");
      if (options_.save_budget && options_.save_budget->bytes_left == 0)
        throw std::logic_error("the server's save budget is used up (restart softevo view)");
      fs::path path;
      do {
        path = fs::path(options_.save_dir) /
               (file_stem(input_.name) + "-view-" + std::to_string(++saves_) + ".h5");
      } while (fs::exists(path) || fs::exists(steering_log_path(path.string())));
      last_save_ = now;
      save_files(path);
      saved_ = true;
      // Only the file's name goes back: the page learns nothing of the machine's paths.
      out.push_back(
          text(json{{"type", "saved"},
                    {"trace", path.filename().string()},
                    {"steering", fs::path(steering_log_path(path.string())).filename().string()}}
                   .dump()));
      break;
    }
  }
  out.push_back(text(state_json()));
  return out;
}

void ClientSession::save_files(const fs::path& path) {
  const std::string log = steering_log_path(path.string());
  try {
    session_->save(path.string(), Overwrite::refuse);
  } catch (const std::exception& e) {
    // The page learns nothing of the machine: the details go to the server's log only.
    if (options_.log) options_.log("the save of " + path.string() + " failed: " + e.what());
    throw std::runtime_error(plain_save_failure(e.what()));
  }
  if (options_.save_budget) {
    std::error_code ec;
    std::uint64_t bytes = 0;
    for (const std::string& p : {path.string(), log}) {
      const auto size = fs::file_size(p, ec);
      if (!ec) bytes += size;
    }
    auto& left = options_.save_budget->bytes_left;
    left = bytes >= left ? 0 : left - bytes;
  }
}

std::vector<Outgoing> ClientSession::tick(double wall_seconds) {
  std::vector<Outgoing> out;
  if (!playing_) return out;
  play_time_ += std::clamp(wall_seconds, 0.0, 1.0) * speed_;
  const auto t0 = std::chrono::steady_clock::now();
  while (!session_->finished() && session_->record(session_->records() - 1).time < play_time_ &&
         std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() <
             options_.max_simulation_seconds_per_tick) {
    session_->advance();
  }
  // The last record at or before the playback time (the simulation may lag behind it).
  int r = shown_ < 0 ? 0 : shown_;
  while (r + 1 < session_->records() && session_->record(r + 1).time <= play_time_ + 1e-9) ++r;
  if (r + 1 >= session_->records() && !session_->finished())
    play_time_ = std::min(play_time_, session_->record(r).time + 1.0 / session_->control_rate());
  show(r, out);
  if (session_->finished() && shown_ == session_->records() - 1) {
    playing_ = false;
    note_end(out);
    out.push_back(text(state_json()));
  }
  return out;
}

}  // namespace softevo::view
