#include "ssl_formation/prediction_message.hpp"

#include <gtest/gtest.h>

namespace ssl_formation {
namespace {

TEST(PredictionMessage, CarriesTheFormationAndEveryStepWithCellCentresInFeedCoordinates) {
  const Grid grid(3, 2);
  TransitionTable table(grid);
  const StateCodec& codec = table.codec();
  std::vector<FormationRobot> robots(1);
  robots[0].robot_id = 4;
  robots[0].feed_position =
      Point{3000, 1000};  // the opponent attacks -x: normalised (-3000, -1000)
  robots[0].position = normalise(robots[0].feed_position, AttackDirection::negative_x);
  const FieldSize field{9000, 6000};
  Formation formation = FormationSampler::build_formation(codec, field, robots, nullptr);
  formation.time_s = 12.0;
  formation.frame_number = 6;
  // Teach it one move: from cell (0,0) to (1,0), centroid along.
  const StateIndex from = formation.robots[0].state;
  const StateIndex to = codec.encode({{1, 0}, {1, 0}, {0, 0}});
  table.add(from, to, 3);
  const Prediction prediction = predict(table, formation, 2);

  PredictionContext context;
  context.codec = &codec;
  context.field = field;
  context.opponent_attacks = AttackDirection::negative_x;
  context.table_transitions = table.transitions();
  proto::FormationPrediction message;
  fill_prediction_message(formation, prediction, context, message);
  proto::FormationPrediction decoded;
  ASSERT_TRUE(decoded.ParseFromString(message.SerializeAsString()));
  EXPECT_EQ(decoded.frame_number(), 6u);
  EXPECT_DOUBLE_EQ(decoded.t_capture(), 12.0);
  ASSERT_EQ(decoded.robots_size(), 1);
  EXPECT_EQ(decoded.robots(0).state_index(), from);
  EXPECT_FLOAT_EQ(decoded.robots(0).position().x(), 3000.0F);
  ASSERT_EQ(decoded.steps_size(), 2);
  const auto& step1 = decoded.steps(0);
  EXPECT_EQ(step1.step(), 1u);
  EXPECT_EQ(step1.centroid_cell().x(), 1u);
  EXPECT_DOUBLE_EQ(step1.centroid_probability(), 1.0);
  EXPECT_EQ(step1.robots(0).state_index(), to);
  EXPECT_EQ(step1.robots(0).position_cell().x(), 1u);
  EXPECT_FALSE(step1.robots(0).unseen());
  // Cell (1,0) is centred at (0, -1500) normalised: (0, 1500) in the feed's coordinates.
  EXPECT_FLOAT_EQ(step1.robots(0).cell_centre().x(), 0.0F);
  EXPECT_FLOAT_EQ(step1.robots(0).cell_centre().y(), 1500.0F);
  EXPECT_TRUE(decoded.steps(1).robots(0).unseen());
  EXPECT_DOUBLE_EQ(decoded.steps(1).confidence(), prediction.steps[1].confidence);
  EXPECT_EQ(decoded.table_transitions(), 3u);
  EXPECT_EQ(decoded.grid_length(), 3u);

  // The predictor's direct encoder writes the very same bytes.
  std::string direct;
  encode_prediction(formation, prediction, context, direct);
  EXPECT_EQ(direct, message.SerializeAsString());

  const std::string line = describe_prediction(formation, prediction);
  EXPECT_NE(line.find("t=12.00 frame=6 now C(0,0) [4:(0,0)] | +1 C(1,0) p=1.000 [4:(1,0)] conf=1"),
            std::string::npos)
      << line;
}

TEST(PredictionMessage, DirectEncodingEqualsTheGeneratedSerialiserOnRandomPredictions) {
  // Large ids, states and counts exercise multi-byte varints; unseen flags and both attack sides.
  for (const Grid grid : {Grid(3, 2), Grid(12, 9), Grid(16, 12)}) {
    TransitionTable table(grid);
    const StateCodec& codec = table.codec();
    const FieldSize field{12000, 9000};
    std::vector<FormationRobot> robots;
    for (std::uint32_t id : {0u, 7u, 200u, 999u}) {
      FormationRobot robot;
      robot.robot_id = id;
      robot.feed_position = Point{-5000.0 + 3.3 * id * id, 4000.0 - 7.7 * id};
      robot.position = robot.feed_position;
      robots.push_back(robot);
    }
    Formation formation = FormationSampler::build_formation(codec, field, robots, nullptr);
    formation.time_s = 1700000000.123;
    formation.frame_number = 4000000000u;
    for (const auto& r : formation.robots) {
      table.add(r.state,
                codec.compose(codec.cell_count() - 1, codec.position_id(r.state),
                              codec.position_id(r.state)),
                300);
    }
    const Prediction prediction = predict(table, formation, 3);
    for (const AttackDirection side : {AttackDirection::positive_x, AttackDirection::negative_x}) {
      PredictionContext context;
      context.codec = &codec;
      context.field = field;
      context.opponent_attacks = side;
      context.opponent_color = TeamColor::blue;
      context.step_s = 0.25;
      context.table_transitions = 1ull << 40;
      proto::FormationPrediction message;
      fill_prediction_message(formation, prediction, context, message);
      std::string direct = "left over from before";
      encode_prediction(formation, prediction, context, direct);
      ASSERT_EQ(direct, message.SerializeAsString()) << grid.to_string();
    }
  }
}

}  // namespace
}  // namespace ssl_formation
