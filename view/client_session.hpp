// What one connected page controls: its own Session (so two pages never disturb each other),
// the play state, the speed and the record shown. Network-free, so that the session logic is
// tested without a socket; view/server.cpp only moves its messages.
#pragma once

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "view/protocol.hpp"
#include "view/session.hpp"

namespace softevo::view {

// A message for the page: JSON text or a binary frame.
struct Outgoing {
  bool binary = false;
  std::string bytes;
};

// What the pages of one server may write with Save, together (shared by their sessions).
struct SaveBudget {
  std::uint64_t bytes_left = 1ULL << 30;  // traces and steering logs [bytes], 1 GiB by default
};

struct ClientOptions {
  std::string save_dir = ".";  // where "save" writes (the page never names a path)
  // Save is bounded: at most this many saves per page, not two within min_save_interval
  // seconds, never the same unchanged session twice, and all pages together within the
  // budget (nullptr: no total bound, for tests and --steering replays).
  int max_saves = 8;
  double min_save_interval_seconds = 2.0;
  std::shared_ptr<SaveBudget> save_budget;
  // Live simulation per tick at most this long [s] of wall clock, so that a slow robot cannot
  // stall the server's other work.
  double max_simulation_seconds_per_tick = 0.05;
  // The ground's grid reaches this far [m] beyond the robot's path, and a new one is sent when
  // the robot comes within half of it of the edge (a live robot walks off any fixed square).
  double terrain_margin_m = kTerrainGridMargin;
  // The server's log (one line per call, no newline): what the page is not told, such as the
  // full error of a failed save. The server writes it to stderr; empty = not logged.
  std::function<void(const std::string&)> log;
};

class ClientSession {
 public:
  ClientSession(const ViewInput& input, ClientOptions options);
  // The session keeps a reference to its input: a temporary would dangle.
  ClientSession(ViewInput&& input, ClientOptions options) = delete;

  // The hello (what is shown: body, names, units, counts) and the first frame.
  std::vector<Outgoing> start();
  // One message from the page; a bad message gives one error reply and changes nothing.
  std::vector<Outgoing> handle(std::string_view text, bool is_text);
  // Wall-clock time passed [s]: advances playback (simulating as needed) and returns the frame
  // to show, if it changed, and the "ended" note when the simulation ends.
  std::vector<Outgoing> tick(double wall_seconds);

  // What the page is told first: the body, names, units and counts (JSON).
  std::string hello() const;
  // Simulates the rest of the session and returns the end note the page would get (JSON).
  std::string run_to_end();

  const Session& session() const { return *session_; }
  bool playing() const { return playing_; }
  double speed() const { return speed_; }
  int shown() const { return shown_; }

 private:
  std::vector<Outgoing> act(const ClientMessage& m);
  void show(int record, std::vector<Outgoing>& out);
  void note_end(std::vector<Outgoing>& out);
  std::string ended_json() const;
  std::string state_json() const;
  nlohmann::json hello_json(const TerrainGrid& ground) const;
  // Writes the trace and steering log; an error names no path of the machine.
  void save_files(const std::filesystem::path& path);

  const ViewInput& input_;
  ClientOptions options_;
  std::unique_ptr<Session> session_;
  bool playing_ = true;
  double speed_ = 1.0;
  double play_time_ = 0.0;  // simulated time the playback has reached [s]
  int shown_ = -1;
  bool end_noted_ = false;
  // Where the page's ground grid lies (its heights dropped once sent; nx = 0: flat, none sent).
  TerrainGrid ground_sent_;
  int saves_ = 0;
  bool saved_ = false;  // this session (since its last reset) is saved
  std::optional<std::chrono::steady_clock::time_point> last_save_;
};

}  // namespace softevo::view
