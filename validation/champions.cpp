// Champion-set evaluation for `softevo champions` and `softevo bench eval`. See champions.hpp.
#include "validation/champions.hpp"

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

#include "tasks/task.hpp"
#include "worker/evaluate.hpp"

namespace softevo::validation {
namespace {

// CPU seconds of the calling thread: the figure that stays meaningful on a shared machine.
double thread_cpu_seconds() {
  timespec t{};
  ::clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

}  // namespace

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
                       Integrator integrator) {
  Config config = parse_config("", "<built-in defaults>", overrides);
  config.task.control = row.robot.controller.closed_loop ? ControlLoop::closed : ControlLoop::open;
  config.task.kind = tasks::default_task_for(row.robot.controller.task_inputs());
  config.physics.integrator = integrator;
  // No wall-clock limit: a report must not depend on how busy the machine is.
  config.run.eval_timeout_seconds = 0.0;
  return config;
}

void evaluate_champions(std::vector<ChampionRow>& rows, const std::vector<std::string>& overrides,
                        Integrator integrator, int jobs,
                        const std::function<void(const ChampionRow&)>& progress) {
  struct Unit {
    std::size_t row;
    int unit;
  };
  std::vector<Config> configs;
  configs.reserve(rows.size());  // the tasks keep references into it
  std::vector<std::unique_ptr<tasks::Task>> row_tasks;
  std::vector<Unit> units;
  std::vector<std::vector<EvalResult>> results(rows.size());
  std::vector<std::vector<double>> cpu(rows.size());
  std::vector<int> remaining(rows.size(), 0);
  for (std::size_t r = 0; r < rows.size(); ++r) {
    configs.push_back(champion_config(rows[r], overrides, integrator));
    row_tasks.push_back(tasks::make_task(configs.back()));
    const int n = row_tasks.back()->units();
    for (int u = 0; u < n; ++u) units.push_back({r, u});
    results[r].resize(static_cast<std::size_t>(n));
    cpu[r].resize(static_cast<std::size_t>(n));
    remaining[r] = n;
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
      EvalResult res = worker::evaluate(configs[u.row], *row_tasks[u.row], row.robot.body,
                                        row.robot.controller, u.unit);
      const double c1 = thread_cpu_seconds();
      const auto slot = static_cast<std::size_t>(u.unit);
      std::lock_guard<std::mutex> lock(mutex);
      results[u.row][slot] = std::move(res);
      cpu[u.row][slot] = c1 - c0;
      if (--remaining[u.row] == 0) {
        row.result = tasks::combine_units(*row_tasks[u.row], results[u.row]);
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

}  // namespace softevo::validation
