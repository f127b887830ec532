// Which candidate discovery accepts: each offered candidate fitted with the base at each weight of its
// priors, pairs of the best candidates of one family on two joints, the transfer statistics, and the rule
// that breaks ties.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>

#include "model/identify/discovery_problem.hpp"

namespace jointcomp::discovery_detail {

FitSystem baseSystem(const LinearisedProblem& problem) {
  std::vector<int> all;
  for (int g = 0; g < problem.refitGrouping(); ++g) all.push_back(g);
  return assembleSystem(problem, {}, all);
}

namespace {

constexpr double kGroupHurt = 0.01;  // a group may be worse by 1 % of its error, or by noise, not more

// The weights cross-validation chooses a prior's from: 0 and five decades up to the most.
std::vector<double> priorWeights(double most) {
  std::vector<double> weights = {0.0};
  for (int k = 4; k >= 0 && most > 0.0; --k) weights.push_back(most * std::pow(10.0, -k));
  return weights;
}

// How much worse a fit predicts a group than the base does, and how sure that is: the change summed over
// the group's sub-blocks, against the spread of the sub-blocks' changes (standard error of the sum).
struct GroupChange {
  double before = 0.0, after = 0.0, standard_error = 0.0;
};
GroupChange groupChange(const GroupingErrors& fit, const GroupingErrors& base, const std::vector<int>& group_of_block,
                        int group) {
  GroupChange c;
  std::vector<double> change;
  for (std::size_t b = 0; b < group_of_block.size(); ++b) {
    if (group_of_block[b] != group) continue;
    c.before += base.block[b];
    c.after += fit.block[b];
    change.push_back(fit.block[b] - base.block[b]);
  }
  const double n = static_cast<double>(change.size());
  if (n > 1) {
    double mean = 0.0, square = 0.0;
    for (double d : change) mean += d / n;
    for (double d : change) square += (d - mean) * (d - mean);
    c.standard_error = std::sqrt(n * square / (n - 1));
  }
  return c;
}

// Empty when the fit predicts every group of each of its groupings (left out) no significantly worse than
// the base; else the first group it hurts, with its size and how many standard errors.
std::string transferHurt(const Selection& s, const FitSystem& system, const Fit& fit) {
  const LinearisedProblem& problem = s.lin.problem;
  for (std::size_t gi = 0; gi < system.groupings.size(); ++gi) {
    const int g = system.groupings[gi];
    const RowGrouping& grouping = problem.groupings[static_cast<std::size_t>(g)];
    for (int group = 0; group < grouping.groups(); ++group) {
      const int rows = grouping.rows_of_group[static_cast<std::size_t>(group)];
      const GroupChange c =
          groupChange(fit.errors[gi], s.base.errors[static_cast<std::size_t>(g)], grouping.group_of_block, group);
      const double worse = c.after - c.before;
      if (worse <= kGroupHurt * c.before || worse <= s.options.transfer_significance * c.standard_error) continue;
      char text[320];
      std::snprintf(text, sizeof(text),
                    "CV error %+.1f %% overall but %+.1f %% on %s %d of %d (%d rows, %.1f standard errors)",
                    100.0 * (fit.cv / s.base.cv - 1.0), 100.0 * (c.after / c.before - 1.0), grouping.kind.c_str(),
                    group + 1, grouping.groups(), rows,
                    c.standard_error > 0.0 ? worse / c.standard_error : std::numeric_limits<double>::infinity());
      return text;
    }
  }
  return {};
}

double partsError(const FitSystem& system, const Fit& fit) {
  double sum = fit.cv;
  for (std::size_t gi = 0; gi < system.groupings.size(); ++gi) {
    if (system.groupings[gi] != 1) continue;
    for (double e : fit.errors[gi].group) sum += e;
  }
  return sum;
}

// The groupings a fit of candidates on these joints is judged on: time blocks, joint-space parts, and the
// angle ranges of each of its joints.
std::vector<int> groupingsFor(const Selection& s, const std::vector<int>& members) {
  std::vector<int> groupings = {0, 1};
  for (int c : members) {
    const int joint = s.features.candidates[static_cast<std::size_t>(c)].joint;
    const int g = s.lin.problem.angleGrouping(joint);
    if (joint >= 0 && std::find(groupings.begin(), groupings.end(), g) == groupings.end()) groupings.push_back(g);
  }
  return groupings;
}

// Fits the members with the base at the given prior weights, and judges the fit.
Evaluation judge(const Selection& s, const FitSystem& system, const std::vector<CandidatePiece>& pieces,
                 const std::vector<int>& members, const std::vector<double>& roughness,
                 const std::vector<double>& ridge) {
  Penalty penalty;
  std::vector<std::vector<int>> own(members.size());
  for (std::size_t m = 0; m < members.size(); ++m) {
    for (int c : pieces[m].coefficients) own[m].push_back(system.piece_first[m + 1] + c);
    const Eigen::MatrixXd& prior = s.features.candidates[static_cast<std::size_t>(members[m])].prior;
    addPrior(system, own[m], prior, roughness[m], Eigen::VectorXd(), penalty);
    if (prior.size() > 0) {
      addPrior(system, own[m], Eigen::MatrixXd::Identity(prior.rows(), prior.cols()), ridge[m], Eigen::VectorXd(),
               penalty);
    }
  }
  Evaluation e;
  e.candidates = members;
  e.roughness_weight = roughness;
  e.ridge_weight = ridge;
  e.fit = solveSystem(system, penalty, false);
  const double residuals = static_cast<double>(s.lin.problem.r.size());
  e.added = e.fit.dof - s.base.dof;
  if (e.added <= 0.0 || e.fit.rss <= 0.0 || s.base.rss <= 0.0) return e;
  const double tried = std::max(1.0, static_cast<double>(s.features.candidates.size()));
  e.delta_bic = residuals * std::log(e.fit.rss / s.base.rss) + e.added * std::log(residuals) + 2.0 * std::log(tried);
  e.gains = e.fit.cv < s.base.cv * (1.0 - s.options.min_cv_gain) && e.delta_bic < 0.0;
  e.hurt = e.gains ? transferHurt(s, system, e.fit) : std::string();
  e.transfer_error = partsError(system, e.fit);
  for (std::size_t m = 0; m < members.size(); ++m) {
    Eigen::VectorXd step(static_cast<Eigen::Index>(own[m].size()));
    for (std::size_t k = 0; k < own[m].size(); ++k)
      step[static_cast<Eigen::Index>(k)] = e.fit.d[own[m][k]] / system.scale[own[m][k]];
    e.member_step.push_back(step);
    const std::size_t c = static_cast<std::size_t>(members[m]);
    if (e.unphysical.empty())
      e.unphysical =
          s.features.family[c]->physicalProblem(s.data, s.features.candidates[c], step, s.cal.estimate.compliance);
  }
  return e;
}

bool better(const Evaluation& a, const Evaluation& b) {
  if (a.passes() != b.passes()) return a.passes();
  return a.transfer_error < b.transfer_error;
}

// One candidate alone, at every weight of its priors; the best weights: those that pass, then the lowest
// error predicted on the time blocks and the joint-space parts together.
Evaluation evaluateAlone(const Selection& s, int c) {
  const std::vector<CandidatePiece> pieces = {candidatePiece(s.lin, s.features, c, s.cal)};
  const FitSystem system = assembleSystem(s.lin.problem, {&pieces[0].piece}, groupingsFor(s, {c}));
  const bool has_prior = s.features.candidates[static_cast<std::size_t>(c)].prior.size() > 0;
  Evaluation best = judge(s, system, pieces, {c}, {0.0}, {0.0});
  if (!has_prior) return best;
  // The two weights by coordinate search: the roughness at a middle ridge, then the ridge at that roughness.
  const std::vector<double> roughness = priorWeights(s.options.max_prior_weight);
  const std::vector<double> ridge = priorWeights(s.options.max_ridge_weight);
  const double middle_ridge = ridge.size() > 2 ? ridge[ridge.size() - 2] : 0.0;
  double chosen_roughness = 0.0;
  for (double w : roughness) {
    Evaluation e = judge(s, system, pieces, {c}, {w}, {middle_ridge});
    if (better(e, best)) {
      best = std::move(e);
      chosen_roughness = w;
    }
  }
  for (double r : ridge) {
    if (r == middle_ridge) continue;
    Evaluation e = judge(s, system, pieces, {c}, {chosen_roughness}, {r});
    if (better(e, best)) best = std::move(e);
  }
  return best;
}

Evaluation evaluatePair(const Selection& s, const Evaluation& a, const Evaluation& b) {
  const std::vector<int> members = {a.candidates[0], b.candidates[0]};
  const std::vector<CandidatePiece> pieces = {candidatePiece(s.lin, s.features, members[0], s.cal),
                                              candidatePiece(s.lin, s.features, members[1], s.cal)};
  const FitSystem system =
      assembleSystem(s.lin.problem, {&pieces[0].piece, &pieces[1].piece}, groupingsFor(s, members));
  return judge(s, system, pieces, members, {a.roughness_weight[0], b.roughness_weight[0]},
               {a.ridge_weight[0], b.ridge_weight[0]});
}

// Whether `fit`'s CV error is statistically tied with `best`'s: within one standard error of the
// fold-wise differences, or within a quarter of the gain a step must bring.
bool tied(const Fit& fit, const Fit& best, double min_cv_gain) {
  const double margin = best.cv * 0.25 * min_cv_gain;
  const std::size_t folds = fit.cv_fold.size();
  double mean = 0.0, square = 0.0;
  for (std::size_t fo = 0; fo < folds; ++fo) {
    const double d = fit.cv_fold[fo] - best.cv_fold[fo];
    mean += d;
    square += d * d;
  }
  mean /= static_cast<double>(folds);
  const double variance = folds > 1 ? (square - folds * mean * mean) / static_cast<double>(folds - 1) : 0.0;
  const double standard_error_of_sum = std::sqrt(std::max(0.0, variance) * static_cast<double>(folds));
  return fit.cv - best.cv <= std::max(margin, standard_error_of_sum);
}

std::string label(const Selection& s, const Evaluation& e) {
  std::string text;
  for (int c : e.candidates)
    text += (text.empty() ? "" : " + ") + s.features.candidates[static_cast<std::size_t>(c)].label();
  return text;
}

// A pair competes only when it helps more than its two members do alone, summed: effects that help only
// together (each hiding the other), not two independent ones, which the greedy steps take one at a time.
constexpr double kPairSynergy = 1.05;

// The pairs worth fitting: per family, the best single candidate of each joint that gains; each two of them,
// where the pair is synergistic.
std::vector<Evaluation> pairs(const Selection& s, const std::vector<Evaluation>& alone) {
  std::map<std::pair<const DiscoveryFamily*, int>, const Evaluation*> best;
  for (const Evaluation& e : alone) {
    const int c = e.candidates[0];
    const int joint = s.features.candidates[static_cast<std::size_t>(c)].joint;
    if (joint < 0 || !e.gains) continue;
    const Evaluation*& slot = best[{s.features.family[static_cast<std::size_t>(c)], joint}];
    if (!slot || e.transfer_error < slot->transfer_error) slot = &e;
  }
  std::vector<Evaluation> out;
  for (auto a = best.begin(); a != best.end(); ++a) {
    for (auto b = std::next(a); b != best.end(); ++b) {
      if (a->first.first != b->first.first) continue;
      Evaluation pair = evaluatePair(s, *a->second, *b->second);
      const double gain_a = s.base.cv - a->second->fit.cv, gain_b = s.base.cv - b->second->fit.cv;
      if (s.base.cv - pair.fit.cv > kPairSynergy * (gain_a + gain_b)) out.push_back(std::move(pair));
    }
  }
  return out;
}

}  // namespace

Choice chooseCandidate(const Selection& s) {
  Choice choice;
  std::vector<Evaluation> all;
  for (std::size_t c = 0; c < s.features.candidates.size(); ++c) {
    if (!s.offered[c]) continue;
    const CandidatePiece piece = candidatePiece(s.lin, s.features, static_cast<int>(c), s.cal);
    if (piece.piece.columns() == 0) continue;
    ++choice.tried;
    all.push_back(evaluateAlone(s, static_cast<int>(c)));
  }
  if (s.options.pairs) {
    std::vector<Evaluation> more = pairs(s, all);
    for (Evaluation& e : more) all.push_back(std::move(e));
  }
  const Evaluation* best = nullptr;
  double runner_cv = std::numeric_limits<double>::infinity(), rejected_cv = runner_cv;
  for (const Evaluation& e : all) {
    if (e.passes() && (!best || e.fit.cv < best->fit.cv)) best = &e;
    if (e.gains && !e.passes() && e.fit.cv < rejected_cv) {
      rejected_cv = e.fit.cv;
      choice.rejected = label(s, e) + ": " + (e.unphysical.empty() ? "does not transfer, " + e.hurt : e.unphysical);
    }
  }
  // Of the candidates tied with the best, the one with the fewest (effective) parameters, then the lowest BIC:
  // an offset rather than the joint's whole placement or a drift that starts from an offset.
  std::vector<const Evaluation*> tied_set;
  double fewest = std::numeric_limits<double>::infinity();
  for (const Evaluation& e : all) {
    if (!best || !e.passes() || !tied(e.fit, best->fit, s.options.min_cv_gain)) continue;
    tied_set.push_back(&e);
    fewest = std::min(fewest, e.added);
  }
  const Evaluation* chosen = nullptr;
  for (const Evaluation* e : tied_set) {
    if (e->added > fewest + 0.5) continue;
    if (!chosen || e->delta_bic < chosen->delta_bic) chosen = e;
  }
  for (const Evaluation& e : all) {
    if (&e != chosen && e.fit.cv < runner_cv && e.added > 0.0) {
      runner_cv = e.fit.cv;
      choice.runner_up = label(s, e);
    }
  }
  if (!chosen) return choice;
  choice.found = true;
  choice.chosen = *chosen;
  return choice;
}

}  // namespace jointcomp::discovery_detail
