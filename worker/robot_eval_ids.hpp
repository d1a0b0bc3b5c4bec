// The evaluation ids a robot file is evaluated with (`softevo eval`, softevo.evaluate,
// softevo.Simulation): with its run's config (the robot file's evaluation block), the generation
// and genome id it was archived with, so that a ground resampled per generation or per
// evaluation (terrain.resample, docs/model.md §2.8a) is the one its run gave it and the archived
// fitness is reproduced; generation 0, genome 0 otherwise.
#pragma once

#include "common/robot.hpp"
#include "worker/evaluate.hpp"
#include "worker/simulation.hpp"

namespace softevo::worker {

inline EvaluationIds robot_eval_ids(const RobotFile& robot, const RobotEvalSettings& settings) {
  if (robot_config_source(robot, settings) != RobotConfigSource::robot_file) return {};
  const RobotEvaluation& e = *robot.evaluation;
  if (!e.generation || !e.id) return {};
  return {*e.generation, *e.id};
}

}  // namespace softevo::worker
