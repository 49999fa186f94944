#include "instance.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <cstdarg>
#include <fstream>
#include <sstream>

#include "entry_point.hpp"
#include "math/number_text.hpp"
#include "model_description.hpp"
#include "resource_uri.hpp"

namespace mfbd {

namespace {

const char* stateName(FmuState s) {
  switch (s) {
    case FmuState::Instantiated: return "Instantiated";
    case FmuState::InitializationMode: return "InitializationMode";
    case FmuState::StepComplete: return "StepComplete";
    case FmuState::StepFailed: return "StepFailed";
    case FmuState::Terminated: return "Terminated";
    case FmuState::Error: return "Error";
  }
  return "?";
}

bool readFile(const std::string& path, std::string& text) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return false;
  std::ostringstream s;
  s << in.rdbuf();
  text = s.str();
  return true;
}

}  // namespace

bool Instance::logs(fmi2Status status, const char* category) const {
  if (!callbacks_.logger) return false;
  // Warnings, errors and discards always reach the importer (a warning
  // says that something the scene asked for was changed); the rest when
  // enabled.
  const bool always = status != fmi2OK;
  return always || (loggingOn_ && (categories_.empty() || categories_.count(category) || categories_.count("logAll")));
}

void Instance::log(fmi2Status status, const char* category, const std::string& message) const {
  if (!logs(status, category)) return;
  callbacks_.logger(callbacks_.componentEnvironment, name_.c_str(), status, category, loggerFormat(message).c_str());
}

fmi2Status Instance::fail(const char* function, const std::string& message) {
  log(fmi2Error, "logStatusError", std::string(function) + ": " + message);
  return fmi2Error;
}

Instance* Instance::create(const std::string& name, const std::string& guid, const std::string& resourceUri,
                           const fmi2CallbackFunctions* callbacks, bool loggingOn) {
  std::unique_ptr<Instance> c(new Instance());
  c->name_ = name;
  if (callbacks) c->callbacks_ = *callbacks;
  c->loggingOn_ = loggingOn;
  std::string dir, why;
  if (!resourceUriToPath(resourceUri, dir, why)) {
    c->fail("fmi2Instantiate", "fmuResourceLocation: " + why);
    return nullptr;
  }
  if (!dir.empty() && dir.back() != '/') dir += '/';
  if (!readFile(dir + "scene.json", c->sceneText_)) {
    c->fail("fmi2Instantiate", "cannot read the scene " + dir + "scene.json");
    return nullptr;
  }
  const std::string expected = sceneGuid(c->sceneText_);
  if (guid != expected) {
    c->fail("fmi2Instantiate", "fmuGUID \"" + guid + "\" does not match this FMU's scene (expected \"" +
                                   expected + "\"): modelDescription.xml and resources/scene.json disagree");
    return nullptr;
  }
  try {
    c->scene_ = parseScene(c->sceneText_);
    Simulation check(c->scene_);  // assembly errors surface here, not later
    c->table_ = variableTable(c->scene_, check.numbering());
  } catch (const SceneError& e) {
    c->fail("fmi2Instantiate", std::string("resources/scene.json: ") + e.what());
    return nullptr;
  }
  c->guid_ = expected;
  c->values_.resize(c->table_.size());
  c->derivative1_.assign(c->table_.size(), 0.0);
  c->derivative2_.assign(c->table_.size(), 0.0);
  for (std::size_t i = 0; i < c->table_.size(); ++i) {
    c->byReference_[c->table_[i].valueReference] = i;
    c->values_[i] = c->table_[i].start;
  }
  for (const std::string& note : c->scene_.notes) c->log(fmi2OK, "logEvents", note);
  c->log(fmi2OK, "logEvents", "instantiated scene '" + c->scene_.name + "' with " +
                                  std::to_string(c->table_.size()) + " variables");
  return c.release();
}

bool Instance::allow(const char* function, unsigned mask) {
  if (static_cast<unsigned>(state_) & mask) return true;
  fail(function, std::string("not allowed in state ") + stateName(state_));
  return false;
}

fmi2Status Instance::setDebugLogging(bool on, std::size_t n, const fmi2String categories[]) {
  std::set<std::string, std::less<>> chosen;
  for (std::size_t i = 0; i < n; ++i) {
    const std::string c = categories && categories[i] ? categories[i] : "";
    bool known = false;
    for (const auto& k : logCategories()) known = known || k.first == c;
    if (!known) return fail("fmi2SetDebugLogging", "unknown log category \"" + c + "\"");
    chosen.insert(c);
  }
  loggingOn_ = on;
  categories_ = chosen;
  return fmi2OK;
}

fmi2Status Instance::setupExperiment(bool toleranceDefined, double tolerance, double startTime, bool stopTimeDefined,
                                     double stopTime) {
  if (!std::isfinite(startTime)) return fail("fmi2SetupExperiment", "startTime must be finite");
  if (stopTimeDefined && !(stopTime >= startTime))
    return fail("fmi2SetupExperiment", "stopTime must be >= startTime");
  if (toleranceDefined && !(tolerance >= 1e-12 && tolerance < 1.0))
    return fail("fmi2SetupExperiment", "tolerance must be a relative tolerance in [1e-12, 1), got " +
                                           numberText(tolerance));
  tolerance_ = toleranceDefined ? tolerance : 0.0;
  startTime_ = startTime;
  stopTimeDefined_ = stopTimeDefined;
  stopTime_ = stopTime;
  return fmi2OK;
}

std::unique_ptr<Simulation> Instance::makeSimulation(const std::vector<double>& values, double tolerance,
                                                     double horizon) const {
  std::map<std::string, double> user;
  bool defaults = true;
  for (std::size_t i = 0; i < table_.size(); ++i)
    if (table_[i].quantity.kind == QuantityKind::UserParameter) {
      user[table_[i].name] = values[i];
      defaults = defaults && values[i] == table_[i].start;
    }
  // The scene parsed at instantiation serves while every user parameter
  // keeps its start value (a parse is most of a small scene's set-up).
  Scene scene = defaults ? scene_ : parseScene(sceneText_, user);
  for (std::size_t i = 0; i < table_.size(); ++i)
    if (table_[i].causality == Causality::Parameter) setSceneParameter(scene, table_[i].quantity, values[i]);
  return std::make_unique<Simulation>(scene, tolerance, horizon);
}

// Scene with the current parameter values -> Simulation at startTime.
bool Instance::buildSimulation(const char* function) {
  try {
    simulation_ = makeSimulation(values_, tolerance_, errorHorizon(stopTimeDefined_, startTime_, stopTime_));
    builtWith_ = values_;
  } catch (const SceneError& e) {
    fail(function, std::string("with the parameter values set: ") + e.what());
    return false;
  }
  for (std::size_t i = 0; i < table_.size(); ++i) {
    if (table_[i].causality != Causality::Input) continue;
    simulation_->write(table_[i].quantity, values_[i]);
    if (derivative1_[i] != 0.0) simulation_->writeDerivative(table_[i].quantity, 1, derivative1_[i]);
    if (derivative2_[i] != 0.0) simulation_->writeDerivative(table_[i].quantity, 2, derivative2_[i]);
  }
  std::string message;
  std::vector<std::string> notes;
  if (!simulation_->initialize(startTime_, message, &notes)) {
    fail(function, "initialization failed: " + message);
    simulation_.reset();
    return false;
  }
  for (const std::string& note : notes) log(fmi2OK, "logEvents", note);
  for (const std::string& warning : simulation_->warnings())
    log(fmi2Warning, "logStatusWarning", std::string(function) + ": " + warning);
  simulationStale_ = false;
  lastSuccessfulTime_ = startTime_;
  return true;
}

fmi2Status Instance::enterInitializationMode() {
  if (!buildSimulation("fmi2EnterInitializationMode")) {
    state_ = FmuState::Error;
    return fmi2Error;
  }
  state_ = FmuState::InitializationMode;
  log(fmi2OK, "logEvents", "initialization mode at t = " + numberText(startTime_));
  return simulation_->warnings().empty() ? fmi2OK : fmi2Warning;
}

fmi2Status Instance::exitInitializationMode() {
  const bool rebuild = simulationStale_ || !simulation_;
  if (rebuild && !buildSimulation("fmi2ExitInitializationMode")) {
    state_ = FmuState::Error;
    return fmi2Error;
  }
  std::string message;
  std::vector<std::string> notes;
  if (!simulation_->startFromEquilibrium(message, &notes)) {
    fail("fmi2ExitInitializationMode", message);
    state_ = FmuState::Error;
    return fmi2Error;
  }
  for (const std::string& note : notes) log(fmi2OK, "logEvents", note);
  state_ = FmuState::StepComplete;
  return rebuild && !simulation_->warnings().empty() ? fmi2Warning : fmi2OK;
}

std::string Instance::solverStatistics() const {
  if (!simulation_) return "no steps";
  const IntegratorState& s = simulation_->state();
  std::ostringstream msg;
  msg << "substeps " << s.substeps << ", Newton iterations " << s.newtonIterations << ", factorizations "
      << s.factorizations << ", rejected " << s.rejectedSubsteps;
  return msg.str();
}

fmi2Status Instance::terminate() {
  state_ = FmuState::Terminated;
  log(fmi2OK, "logEvents", "terminated at t = " + numberText(currentTime()));
  if (logs(fmi2OK, "logStatistics"))
    log(fmi2OK, "logStatistics", "t = " + numberText(currentTime()) + ": " + solverStatistics());
  return fmi2OK;
}

fmi2Status Instance::reset() {
  simulation_.reset();
  simulationStale_ = true;
  for (std::size_t i = 0; i < table_.size(); ++i) values_[i] = table_[i].start;
  std::fill(derivative1_.begin(), derivative1_.end(), 0.0);
  std::fill(derivative2_.begin(), derivative2_.end(), 0.0);
  startTime_ = 0.0;
  stopTimeDefined_ = false;
  tolerance_ = 0.0;
  lastSuccessfulTime_ = 0.0;
  terminatedBySlave_ = false;
  state_ = FmuState::Instantiated;
  log(fmi2OK, "logEvents", "reset to start values");
  return fmi2OK;
}

double Instance::currentTime() const { return simulation_ ? simulation_->time() : startTime_; }

fmi2Status Instance::getReal(const fmi2ValueReference vr[], std::size_t n, fmi2Real value[]) {
  if (n > 0 && (!vr || !value)) return fail("fmi2GetReal", "null array argument");
  if ((simulationStale_ || !simulation_) && state_ == FmuState::InitializationMode &&
      !buildSimulation("fmi2GetReal"))
    return fmi2Error;
  // Every reference is checked before any value is written.
  for (std::size_t i = 0; i < n; ++i) {
    const auto it = byReference_.find(vr[i]);
    if (it == byReference_.end())
      return fail("fmi2GetReal", "no Real variable with value reference " + std::to_string(vr[i]));
    const Variable& v = table_[it->second];
    // In state Error (only a failed initialization leads there) no state
    // is valid: the outputs have no value, parameters and inputs keep theirs.
    if (v.causality == Causality::Output && (state_ == FmuState::Error || !simulation_))
      return fail("fmi2GetReal", "output '" + v.name + "' has no value in state " + stateName(state_) +
                                     " (the initialization failed; see the earlier error)");
  }
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t k = byReference_.find(vr[i])->second;
    const Variable& v = table_[k];
    if (v.causality != Causality::Output) {
      value[i] = values_[k];
      continue;
    }
    value[i] = simulation_->read(v.quantity);
    if (!std::isfinite(value[i])) {
      value[i] = 0.0;
      return fail("fmi2GetReal", "output '" + v.name + "' is not finite");
    }
  }
  return fmi2OK;
}

bool Instance::checkValue(const Variable& v, double value, std::string& why) const {
  if (!std::isfinite(value)) {
    why = "expected a finite value";
    return false;
  }
  switch (v.quantity.kind) {
    case QuantityKind::StepSizeMax:
      // Below the scene's h_min no substep is allowed at all.
      if (value >= scene_.solver.hMin) return true;
      why = "expected h_max >= solver.h_min = " + numberText(scene_.solver.hMin) + " s";
      return false;
    case QuantityKind::MaxSubsteps:
      if (value >= 1.0 && value <= kMaxSubstepsLimit && value == std::floor(value)) return true;
      why = "expected a whole number from 1 to " + numberText(kMaxSubstepsLimit);
      return false;
    case QuantityKind::SpectralRadius:
      if (value >= 0.0 && value <= 1.0) return true;
      why = "expected a spectral radius in [0, 1]";
      return false;
    case QuantityKind::NewtonTolerance:
      if (value > 0.0) return true;
      why = "expected a Newton tolerance > 0";
      return false;
    case QuantityKind::JointDamping:
    case QuantityKind::FlexibleDamping:
      if (value >= 0.0 && value <= kLargestNumber) return true;
      why = "expected damping in 0.." + numberText(kLargestNumber) + " (the range of scene numbers)";
      return false;
    case QuantityKind::Gravity:
      if (std::abs(value) <= kLargestNumber) return true;
      why = "expected a magnitude of at most " + numberText(kLargestNumber) + " m/s^2 (the range of scene numbers)";
      return false;
    default: return true;  // user parameters: checkScene, all together
  }
}

std::map<std::string, double> Instance::userParameterValues() const {
  std::map<std::string, double> values;
  for (std::size_t i = 0; i < table_.size(); ++i)
    if (table_[i].quantity.kind == QuantityKind::UserParameter) values[table_[i].name] = values_[i];
  return values;
}

bool Instance::checkScene(const std::map<std::string, double>& userValues, std::string& why) const {
  try {
    Simulation check(parseScene(sceneText_, userValues));
  } catch (const SceneError& e) {
    why = std::string("the scene would be invalid: ") + e.what();
    return false;
  }
  return true;
}

fmi2Status Instance::setReal(const fmi2ValueReference vr[], std::size_t n, const fmi2Real value[]) {
  if (n > 0 && (!vr || !value)) return fail("fmi2SetReal", "null array argument");
  const bool running = state_ == FmuState::StepComplete;
  // Every reference and value is checked before any is applied: a refused
  // call changes nothing.
  std::vector<std::size_t> index(n);
  std::string userChanges;
  for (std::size_t i = 0; i < n; ++i) {
    const auto it = byReference_.find(vr[i]);
    if (it == byReference_.end())
      return fail("fmi2SetReal", "no Real variable with value reference " + std::to_string(vr[i]));
    const Variable& v = table_[it->second];
    if (v.causality == Causality::Output) return fail("fmi2SetReal", "'" + v.name + "' is an output");
    if (running && v.variability == Variability::Fixed)
      return fail("fmi2SetReal",
                  "'" + v.name + "' is a fixed parameter; it can be set only before fmi2ExitInitializationMode");
    std::string why;
    if (!checkValue(v, value[i], why))
      return fail("fmi2SetReal", "'" + v.name + "' = " + numberText(value[i]) + ": " + why);
    if (v.quantity.kind == QuantityKind::UserParameter)
      userChanges += (userChanges.empty() ? "'" : ", '") + v.name + "' = " + numberText(value[i]);
    index[i] = it->second;
  }
  // User parameters of the call are checked together against the scene
  // (only then: inputs set at every communication point cost no scene check).
  if (!userChanges.empty()) {
    std::map<std::string, double> userValues = userParameterValues();
    for (std::size_t i = 0; i < n; ++i)
      if (table_[index[i]].quantity.kind == QuantityKind::UserParameter) userValues[table_[index[i]].name] = value[i];
    std::string why;
    if (!checkScene(userValues, why)) return fail("fmi2SetReal", userChanges + ": " + why);
  }
  for (std::size_t i = 0; i < n; ++i) {
    const Variable& v = table_[index[i]];
    values_[index[i]] = value[i];
    derivative1_[index[i]] = derivative2_[index[i]] = 0.0;  // an input's value restarts its derivatives
    if (v.variability == Variability::Fixed) simulationStale_ = true;
    else if (simulation_) simulation_->write(v.quantity, value[i]);
  }
  return fmi2OK;
}

fmi2Status Instance::noVariablesOfType(const char* function, const char* type, std::size_t n,
                                       const fmi2ValueReference vr[]) {
  if (n == 0) return fmi2OK;
  if (!vr) return fail(function, "null array argument");
  return fail(function, std::string("no ") + type + " variable with value reference " +
                            std::to_string(vr[0]) + " (this FMU has Real variables only)");
}

// Times that differ by round-off are the same time: a master that computes
// t0 + n H, t += H or integer nanoseconds lands within a few ulps of the
// largest of the times it adds (t0 and t).
double Instance::timeRoundOff(double t, double now) const {
  const double scale = std::max({std::abs(t), std::abs(now), std::abs(startTime_)});
  return 8.0 * std::numeric_limits<double>::epsilon() * scale;
}

fmi2Status Instance::doStep(double t, double H) {
  if (!simulation_) return fail("fmi2DoStep", "no simulation (initialization did not complete)");
  const double now = simulation_->time();
  if (!std::isfinite(H) || H <= 0.0)
    return fail("fmi2DoStep", "communicationStepSize must be finite and > 0, got " + numberText(H));
  if (!std::isfinite(t) || !(std::abs(t - now) <= timeRoundOff(t, now)))
    return fail("fmi2DoStep", "currentCommunicationPoint " + numberText(t) + " is not the FMU's time " +
                                  numberText(now) + " (to round-off)");
  const double end = t + H;
  if (!std::isfinite(end))
    return fail("fmi2DoStep", "currentCommunicationPoint + communicationStepSize = " + numberText(t) + " + " +
                                  numberText(H) + " is not a finite time");
  // A master that adds up its steps may pass stopTime by its sum's drift.
  if (stopTimeDefined_ && end > stopTime_ + 1e-9 * std::max(1.0, std::abs(stopTime_)))
    return fail("fmi2DoStep", "the step would pass stopTime " + numberText(stopTime_));
  const AdvanceResult result = simulation_->doStep(t, H);
  if (!result.ok) {
    state_ = FmuState::StepFailed;
    lastSuccessfulTime_ = simulation_->time();
    terminatedBySlave_ = true;
    log(fmi2Discard, "logStatusDiscard",
        "fmi2DoStep: " + result.message + "; state restored to t = " + numberText(lastSuccessfulTime_));
    return fmi2Discard;
  }
  lastSuccessfulTime_ = simulation_->time();
  if (result.errorRejections > 0 && logs(fmi2OK, "logStep"))
    log(fmi2OK, "logStep", numberText(double(result.errorRejections)) +
                               " substeps rejected for their error estimate; the last at " + result.lastRejection);
  if (logs(fmi2OK, "logStep"))
    log(fmi2OK, "logStep", "t = " + numberText(simulation_->time()) + ": " + solverStatistics());
  return fmi2OK;
}

fmi2Status Instance::getRealStatus(int kind, fmi2Real* value) {
  if (!value) return fail("fmi2GetRealStatus", "null value argument");
  if (kind != fmi2LastSuccessfulTime) return fail("fmi2GetRealStatus", "only fmi2LastSuccessfulTime is available");
  *value = lastSuccessfulTime_;
  return fmi2OK;
}

fmi2Status Instance::getBooleanStatus(int kind, fmi2Boolean* value) {
  if (!value) return fail("fmi2GetBooleanStatus", "null value argument");
  if (kind != fmi2Terminated) return fail("fmi2GetBooleanStatus", "only fmi2Terminated is available");
  *value = terminatedBySlave_ ? fmi2True : fmi2False;
  return fmi2OK;
}

fmi2Status Instance::unsupported(const char* function, const char* why) { return fail(function, why); }

}  // namespace mfbd
