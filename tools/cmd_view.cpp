// `softevo view`: watch and steer a robot in the browser (view/server.hpp), or write the
// session as one self-contained HTML file (view/export_html.hpp), or re-simulate a steering log
// headless and save the trace it gives (a steered session replayed).
#include <spawn.h>
#include <sys/wait.h>

#include <cstdio>
#include <fstream>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "common/input_file.hpp"
#include "common/printable.hpp"
#include "common/round_trip.hpp"
#include "common/safe_write.hpp"
#include "tools/commands.hpp"
#include "tools/elite_cell.hpp"
#include "view/client_session.hpp"
#include "view/export_html.hpp"
#include "view/server.hpp"
#include "view/session.hpp"

extern char** environ;

namespace softevo::cli {

namespace {

struct ViewArgs {
  std::string input;
  view::ViewRequest request;
  bool best = false;
  std::string cell;  // a MAP-Elites run: the elite of this cell (tools/elite_cell.hpp)
  int port = 8765;
  std::string bind = "127.0.0.1";
  bool open = false;
  int max_clients = 4;
  std::string save_dir = ".";
  std::string web_dir = SOFTEVO_VIEW_WEB_DIR;
  std::string export_html;
  double fps = 30.0;
  std::string steering;    // steering log to replay headless
  std::string save_trace;  // where that replay's trace goes
  bool force = false;
  bool json = false;  // one JSON object per result (a saved file, the server's address)
};

std::string read_steering_log(const std::string& path) {
  return read_input_file(path, InputLimits::steering_log_bytes, "steering log");
}

// The desktop's browser, when there is one (a cluster node has none: the URL is printed anyway).
void open_browser(const std::string& url) {
  pid_t pid = 0;
  const char* argv[] = {"xdg-open", url.c_str(), nullptr};
  if (posix_spawnp(&pid, "xdg-open", nullptr, nullptr, const_cast<char* const*>(argv), environ) !=
      0) {
    std::fprintf(stderr, "softevo view: --open: xdg-open not found; open %s yourself\n",
                 url.c_str());
  }
}

int run_view(const ViewArgs& args) {
  const Overwrite overwrite = args.force ? Overwrite::replace : Overwrite::refuse;
  if (!args.steering.empty() != !args.save_trace.empty())
    throw std::invalid_argument("view: --steering and --save-trace go together");
  if (!args.export_html.empty()) check_output_target(args.export_html, overwrite);
  if (!args.save_trace.empty()) {
    check_output_target(args.save_trace, overwrite);
    check_output_target(view::steering_log_path(args.save_trace), overwrite);
  }
  const view::ViewInput input = view::load_view_input(args.input, args.request);

  if (!args.save_trace.empty()) {
    view::Session session(
        input, view::parse_steering_log(read_steering_log(args.steering), args.steering));
    while (session.advance()) {
    }
    session.save(args.save_trace, overwrite);
    if (args.json) {
      nlohmann::ordered_json j;
      j["trace"] = args.save_trace;
      j["steering_log"] = view::steering_log_path(args.save_trace);
      j["records"] = session.records();
      j["status"] = to_string(session.status());
      j["fitness"] = session.result()->fitness;
      std::printf("%s\n", j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace).c_str());
      return kExitOk;
    }
    std::printf("wrote %s and %s (%d records, status %s, fitness %s)\n", args.save_trace.c_str(),
                view::steering_log_path(args.save_trace).c_str(), session.records(),
                to_string(session.status()), round_trip(session.result()->fitness).c_str());
    return kExitOk;
  }

  view::ClientOptions client;
  client.save_dir = args.save_dir;
  if (!args.export_html.empty()) {
    view::ClientSession session(input, client);
    const std::string page = view::export_html(session, args.web_dir, args.fps);
    write_file_atomically(args.export_html, page, overwrite);
    if (args.json) {
      nlohmann::ordered_json j;
      j["html"] = args.export_html;
      j["bytes"] = page.size();
      j["records"] = session.session().records();
      j["fps"] = args.fps;
      std::printf("%s\n", j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace).c_str());
      return kExitOk;
    }
    std::printf("wrote %s (%.2f MB, %d records shown at %.0f fps)\n", args.export_html.c_str(),
                static_cast<double>(page.size()) / 1e6, session.session().records(), args.fps);
    return kExitOk;
  }

  view::ServerOptions options;
  options.bind = args.bind;
  options.port = args.port;
  options.max_clients = args.max_clients;
  options.web_dir = args.web_dir;
  options.client = client;
  view::Server server(input, options);
  // Escaped: a robot name may carry terminal control sequences (title, clear screen).
  if (!args.json)
    std::printf("softevo view: %s (%s %s) at %s\n", printable(input.name).c_str(),
                softevo::to_string(input.kind), printable(args.input).c_str(),
                server.url().c_str());
  if (!server.loopback_only())
    std::fprintf(stderr,
                 "softevo view: warning: --bind %s is reachable from other machines: anyone who "
                 "reaches port %d can watch and drive the simulation and save into --save-dir "
                 "(no password, no encryption); the default 127.0.0.1 with an SSH port forward "
                 "is safer\n",
                 args.bind.c_str(), server.port());
  if (args.json) {
    // One line on start, for a script that starts the server and then connects to it (with
    // --port 0 it is the only way to learn the port).
    nlohmann::ordered_json j;
    j["url"] = server.url();
    j["bind"] = args.bind;
    j["port"] = server.port();
    j["input"] = args.input;
    j["name"] = input.name;
    j["kind"] = softevo::to_string(input.kind);
    j["loopback_only"] = server.loopback_only();
    std::printf("%s\n", j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace).c_str());
  } else {
    if (args.bind == "127.0.0.1")
      std::printf("  from another machine: ssh -L %d:127.0.0.1:%d THIS_HOST, then open %s\n",
                  server.port(), server.port(), server.url().c_str());
    std::printf("  Ctrl-C stops the server\n");
  }
  std::fflush(stdout);
  if (args.open) open_browser(server.url());
  server.run();
  return kExitOk;
}

}  // namespace

void register_view(CLI::App& app, int& exit_code) {
  auto* cmd = app.add_subcommand(
      "view",
      "watch a robot in the browser (live simulation, steering, plots, replays) through a local "
      "HTTP + WebSocket server, or --export-html one self-contained page");
  auto args = std::make_shared<ViewArgs>();
  cmd->add_option("INPUT", args->input, "ROBOT.json, RUN.h5 or TRACE.h5")->required();
  add_individual_options(*cmd, args->request.generation, args->request.id, args->best, &args->cell,
                         "archive: ");
  cmd->add_option("--config", args->request.config_file,
                  "robot file: config to simulate with (default: the robot file's run config, "
                  "else the built-in thesis values)");
  cmd->add_option("--set", args->request.overrides,
                  "robot file: config override section.key=value");
  cmd->add_option("--task", args->request.task,
                  "robot file: task (gait | directed | rotate; default: the one the controller's "
                  "inputs fit)")
      ->check(CLI::IsMember(choice_names<TaskKind>()));
  add_seconds_option(*cmd, args->request.seconds, "simulated seconds");
  cmd->add_option("--direction", args->request.direction_deg,
                  "directed task: initial target direction [deg, counter-clockwise]")
      ->check(finite_in(-180.0, 180.0));
  cmd->add_option("--robot", args->request.robot_file,
                  "trace: robot file giving the chamber cells when the trace has none");
  cmd->add_option("--port", args->port, "TCP port (default 8765; 0 = any free port)")
      ->check(CLI::Range(0, 65535));
  cmd->add_option("--bind", args->bind,
                  "address to listen on (default 127.0.0.1: this machine only; use an SSH port "
                  "forward from elsewhere)");
  cmd->add_flag("--json", args->json,
                "print one JSON object: the server's url, bind and port on start (one line), or "
                "what --export-html / --save-trace wrote");
  cmd->add_flag("--open", args->open, "open the page in the desktop's browser (xdg-open)");
  cmd->add_option("--max-clients", args->max_clients, "pages connected at once (default 4)")
      ->check(CLI::Range(1, 64));
  cmd->add_option("--save-dir", args->save_dir,
                  "where the page's Save writes the trace and steering log (default: here)");
  cmd->add_option("--web-dir", args->web_dir,
                  "the page's folder (default: view/web of the source)");
  cmd->add_option("--export-html", args->export_html,
                  "write one self-contained HTML replay (three.js, page and frames embedded)");
  cmd->add_option("--fps", args->fps, "--export-html: frames per simulated second (default 30)")
      ->check(finite_in(1.0, 240.0));
  cmd->add_option("--steering", args->steering,
                  "re-simulate with this steering log (X.steering.json) headless; needs "
                  "--save-trace");
  cmd->add_option("--save-trace", args->save_trace,
                  "with --steering: write the replayed trace here (and its steering log beside)");
  cmd->add_flag("--force", args->force, "replace existing output files");
  cmd->callback([&exit_code, args] {
    if (args->request.seconds &&
        !(*args->request.seconds >= 0.0 && *args->request.seconds <= 3600.0))
      throw std::invalid_argument("view: --seconds must be within [0, 3600]");
    select_cell(args->input, args->cell, args->request.generation, args->request.id);
    exit_code = run_view(*args);
  });
}

}  // namespace softevo::cli
