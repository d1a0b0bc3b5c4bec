// Champion-set evaluation for `softevo champions` and `softevo bench eval`.
#include "tools/champion_eval.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <ctime>
#include <filesystem>
#include <limits>
#include <mutex>
#include <stdexcept>
#include <thread>

#include <nlohmann/json.hpp>

#include "tools/bench_common.hpp"
#include "worker/evaluate_robot.hpp"
#include "worker/fitness.hpp"

namespace softevo::cli {

std::vector<std::string> robot_files(const std::string& dir) {
  namespace fs = std::filesystem;
  if (!fs::is_directory(dir)) throw std::runtime_error(dir + ": not a directory");
  std::vector<std::string> files;
  for (const auto& e : fs::directory_iterator(dir))
    if (e.is_regular_file() && e.path().extension() == ".json") files.push_back(e.path().string());
  std::sort(files.begin(), files.end());
  return files;
}

ChampionRow load_champion(const std::string& path) {
  ChampionRow row;
  row.file = path;
  row.robot = read_robot_file(path);
  if (row.robot.name.empty()) row.robot.name = std::filesystem::path(path).stem().string();
  if (!row.robot.reference_json.empty()) {
    const auto ref = nlohmann::json::parse(row.robot.reference_json);
    if (ref.contains("fitness") && ref["fitness"].is_number()) {
      row.has_reference = true;
      row.ref_fitness = ref["fitness"].get<double>();
    }
    if (ref.contains("killed") && ref["killed"].is_boolean())
      row.ref_killed = ref["killed"].get<bool>();
    if (ref.contains("cpu_seconds") && ref["cpu_seconds"].is_number())
      row.ref_cpu_seconds = ref["cpu_seconds"].get<double>();
    if (ref.contains("per_direction") && ref["per_direction"].is_array())
      for (const auto& v : ref["per_direction"])
        if (v.is_number()) row.ref_per_direction.push_back(v.get<double>());
  }
  return row;
}

Config champion_config(const ChampionRow& row, const std::vector<std::string>& overrides,
                       const std::string& integrator, bool gait_only) {
  Config config = parse_config("", "<built-in defaults>", overrides);
  config.task.control = row.robot.controller.closed_loop ? "closed" : "open";
  config.task.kind = row.robot.controller.directed && !gait_only ? "directed" : "gait";
  if (!integrator.empty()) config.physics.integrator = integrator;
  // No wall-clock limit: a report must not depend on how busy the machine is.
  config.run.eval_timeout_seconds = 0.0;
  return config;
}

void evaluate_champions(std::vector<ChampionRow>& rows, const std::vector<std::string>& overrides,
                        const std::string& integrator, bool gait_only, int jobs,
                        const std::function<void(const ChampionRow&)>& progress) {
  struct Unit {
    std::size_t row;
    int direction;  // -1 gait
  };
  std::vector<Config> configs;
  std::vector<Unit> units;
  std::vector<std::vector<EvalResult>> results(rows.size());
  std::vector<std::vector<double>> cpu(rows.size());
  std::vector<int> remaining(rows.size(), 0);
  for (std::size_t r = 0; r < rows.size(); ++r) {
    configs.push_back(champion_config(rows[r], overrides, integrator, gait_only));
    const Config& c = configs.back();
    if (c.task.kind == "directed") {
      for (int d = 0; d < static_cast<int>(c.task.directions.size()); ++d) units.push_back({r, d});
      results[r].resize(c.task.directions.size());
      cpu[r].resize(c.task.directions.size());
      remaining[r] = static_cast<int>(c.task.directions.size());
    } else {
      units.push_back({r, -1});
      results[r].resize(1);
      cpu[r].resize(1);
      remaining[r] = 1;
    }
  }
  std::atomic<std::size_t> next{0};
  std::mutex mutex;
  auto worker = [&] {
    for (;;) {
      const std::size_t i = next.fetch_add(1);
      if (i >= units.size()) return;
      const Unit u = units[i];
      ChampionRow& row = rows[u.row];
      const double c0 = thread_cpu_seconds();
      EvalResult res =
          evaluate_robot(configs[u.row], row.robot.body, row.robot.controller, u.direction);
      const double c1 = thread_cpu_seconds();
      const std::size_t slot = u.direction < 0 ? 0 : static_cast<std::size_t>(u.direction);
      std::lock_guard<std::mutex> lock(mutex);
      results[u.row][slot] = std::move(res);
      cpu[u.row][slot] = c1 - c0;
      if (--remaining[u.row] == 0) {
        row.result =
            u.direction < 0 ? results[u.row][0] : worker::combine_directions(results[u.row]);
        row.cpu_seconds = 0.0;
        for (double c : cpu[u.row]) row.cpu_seconds += c;
        if (progress) progress(row);
      }
    }
  };
  std::vector<std::thread> threads;
  for (int t = 0; t < std::max(1, jobs); ++t) threads.emplace_back(worker);
  for (auto& t : threads) t.join();
}

namespace {

std::vector<double> ranks(const std::vector<double>& v) {
  std::vector<std::size_t> order(v.size());
  for (std::size_t i = 0; i < v.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return v[a] < v[b]; });
  std::vector<double> r(v.size());
  for (std::size_t i = 0; i < order.size();) {
    std::size_t j = i;
    while (j + 1 < order.size() && v[order[j + 1]] == v[order[i]]) ++j;
    const double avg = 0.5 * static_cast<double>(i + j) + 1.0;  // average 1-based rank of ties
    for (std::size_t k = i; k <= j; ++k) r[order[k]] = avg;
    i = j + 1;
  }
  return r;
}

}  // namespace

double spearman(const std::vector<double>& x, const std::vector<double>& y) {
  if (x.size() != y.size() || x.size() < 2) return std::numeric_limits<double>::quiet_NaN();
  const std::vector<double> rx = ranks(x), ry = ranks(y);
  const double n = static_cast<double>(x.size());
  double mx = 0, my = 0;
  for (std::size_t i = 0; i < x.size(); ++i) mx += rx[i], my += ry[i];
  mx /= n;
  my /= n;
  double sxy = 0, sxx = 0, syy = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    sxy += (rx[i] - mx) * (ry[i] - my);
    sxx += (rx[i] - mx) * (rx[i] - mx);
    syy += (ry[i] - my) * (ry[i] - my);
  }
  return sxy / std::sqrt(sxx * syy);
}

double median(std::vector<double> v) {
  if (v.empty()) return std::numeric_limits<double>::quiet_NaN();
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

}  // namespace softevo::cli
