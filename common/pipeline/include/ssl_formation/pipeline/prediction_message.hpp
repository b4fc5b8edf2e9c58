#pragma once
// Converts a formation and its prediction into the FormationPrediction message the predictor
// multicasts, and into the one readable line it prints.

#include <string>

#include "formation_prediction.pb.h"
#include "ssl_formation/base/formation.hpp"
#include "ssl_formation/base/prediction.hpp"
#include "ssl_formation/match/game_phase.hpp"
#include "ssl_formation/match/referee.hpp"
#include "ssl_formation/models/model_factory.hpp"

namespace ssl_formation {
inline namespace pipeline {

struct PredictionContext {
  const StateCodec* codec = nullptr;
  FieldSize field;
  AttackDirection opponent_attacks = AttackDirection::positive_x;
  TeamColor opponent_color = TeamColor::yellow;
  double step_s = 2.0;
  std::uint64_t table_transitions = 0;
  ModelKind model = default_model;
  GameState game_state = GameState::unknown;  // the referee's, when the prediction was made
  GamePhase phase = GamePhase::running;       // the phase for the team predicted, then
};

// Fills `out` (cleared first; reusing one message avoids allocation per packet). Every step
// carries its horizon_seconds (step x context.step_s) and the message its model; a predicted
// robot carries position, radius_50_mm and radius_90_mm only when its radius90_mm is above 0
// (the motion model), so the paper model's robots carry only their cells.
void fill_prediction_message(const Formation& current, const Prediction& prediction,
                             const PredictionContext& context, proto::FormationPrediction& out);

// Writes exactly the bytes fill_prediction_message + SerializeToString would give, straight from
// the formation and prediction into `out` (cleared first, capacity kept). The predictor's hot path
// uses this: building ~60 nested messages and serialising them costs several microseconds when
// the caches are cold (one packet every 16 ms), writing the wire format directly does not.
void encode_prediction(const Formation& current, const Prediction& prediction,
                       const PredictionContext& context, std::string& out);

// "t=12.00 frame=6 now C(1,1) [0:(0,1) 1:(1,0) ...] | +1 C(2,1) p=0.82 [0:(1,1) ...] conf=0.412 |
// +2 ..."
std::string describe_prediction(const Formation& current, const Prediction& prediction);
// A short line for a person watching (under 200 characters): the instant, the game state, the
// model, how many robots, and per step how far ahead, the mean 90% radius (motion model) and the
// formation's probability.
std::string summarize_prediction(const Formation& current, const Prediction& prediction,
                                 const PredictionContext& context);
// The same with what the context knows. For the paper's model the line above; for the motion
// model each step is labelled with its horizon and each robot gives its predicted position in the
// feed's coordinates (mm, '?' when no counts backed it), the radius holding it with 90%
// probability and the probability of its predicted cell:
// "t=12.00 frame=6 now C(1,1) [...] | +2.0s C(2,1) p=0.820 [r3 (1234,-567) r90=420mm p=0.62,
// r5 ...] conf=0.412 | +4.0s ..."
std::string describe_prediction(const Formation& current, const Prediction& prediction,
                                const PredictionContext& context);

}  // namespace pipeline
}  // namespace ssl_formation
