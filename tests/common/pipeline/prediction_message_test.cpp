#include "ssl_formation/pipeline/prediction_message.hpp"

#include <gtest/gtest.h>

#include "ssl_formation/paper_model/predictor.hpp"

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
  context.model = ModelKind::paper;
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
  // Every step says how far ahead it is, the message which model; the paper's robots state no
  // position or radii beyond their cells.
  EXPECT_EQ(decoded.model(), "paper");
  EXPECT_TRUE(step1.has_horizon_seconds());
  EXPECT_EQ(step1.horizon_seconds(), 2.0);
  EXPECT_EQ(decoded.steps(1).horizon_seconds(), 4.0);
  EXPECT_FALSE(step1.robots(0).has_position());
  EXPECT_FALSE(step1.robots(0).has_radius_50_mm());
  EXPECT_FALSE(step1.robots(0).has_radius_90_mm());

  // The predictor's direct encoder writes the very same bytes.
  std::string direct;
  encode_prediction(formation, prediction, context, direct);
  EXPECT_EQ(direct, message.SerializeAsString());

  const std::string line = describe_prediction(formation, prediction);
  EXPECT_NE(line.find("t=12.00 frame=6 now C(0,0) [4:(0,0)] | +1 C(1,0) p=1.000 [4:(1,0)] conf=1"),
            std::string::npos)
      << line;
  // With the context, the paper's line is the same.
  EXPECT_EQ(describe_prediction(formation, prediction, context), line);
}

// A prediction as the motion model makes it: positions in the feed's mm and radii.
Prediction with_motion(Prediction prediction) {
  double x = -4321.25;
  for (std::size_t k = 0; k < prediction.steps.size(); ++k) {
    for (RobotPrediction& robot : prediction.steps[k].robots) {
      robot.feed_position = Point{x, 1234.567 - 0.5 * x};
      robot.radius50_mm = 150.3 + 200.0 * static_cast<double>(k);
      robot.radius90_mm = 419.6 + 400.0 * static_cast<double>(k);
      robot.mean_square_mm2 = robot.radius50_mm * robot.radius50_mm;
      x += 1111.1;
    }
  }
  return prediction;
}

TEST(PredictionMessage, TheMotionModelsRobotsCarryTheirPositionsAndRadii) {
  const Grid grid(3, 2);
  TransitionTable table(grid);
  const StateCodec& codec = table.codec();
  const FieldSize field{9000, 6000};
  std::vector<FormationRobot> robots(2);
  robots[0].robot_id = 3;
  robots[0].feed_position = Point{-3000, -1000};
  robots[0].position = robots[0].feed_position;
  robots[1].robot_id = 5;
  robots[1].feed_position = Point{2000, 1500};
  robots[1].position = robots[1].feed_position;
  Formation formation = FormationSampler::build_formation(codec, field, robots, nullptr);
  formation.time_s = 12.0;
  formation.frame_number = 6;
  const Prediction prediction = with_motion(predict(table, formation, 3));

  PredictionContext context;
  context.codec = &codec;
  context.field = field;
  context.step_s = 0.1;
  context.model = ModelKind::motion;
  proto::FormationPrediction message;
  fill_prediction_message(formation, prediction, context, message);
  proto::FormationPrediction decoded;
  ASSERT_TRUE(decoded.ParseFromString(message.SerializeAsString()));
  EXPECT_EQ(decoded.model(), "motion");
  ASSERT_EQ(decoded.steps_size(), 3);
  for (int k = 0; k < 3; ++k) {
    const proto::PredictedStep& step = decoded.steps(k);
    EXPECT_EQ(step.horizon_seconds(), static_cast<double>(k + 1) * 0.1);  // 3 x 0.1, not 0.3
    ASSERT_EQ(step.robots_size(), 2);
    for (int i = 0; i < 2; ++i) {
      const RobotPrediction& robot =
          prediction.steps[static_cast<std::size_t>(k)].robots[static_cast<std::size_t>(i)];
      const proto::PredictedRobot& r = step.robots(i);
      ASSERT_TRUE(r.has_position());
      EXPECT_EQ(r.position().x(), static_cast<float>(robot.feed_position.x));
      EXPECT_EQ(r.position().y(), static_cast<float>(robot.feed_position.y));
      EXPECT_EQ(r.radius_50_mm(), static_cast<float>(robot.radius50_mm));
      EXPECT_EQ(r.radius_90_mm(), static_cast<float>(robot.radius90_mm));
    }
  }
  std::string direct;
  encode_prediction(formation, prediction, context, direct);
  EXPECT_EQ(direct, message.SerializeAsString());

  // The line: horizons in seconds, positions in mm, the 90% radius and the cell's probability.
  const std::string line = describe_prediction(formation, prediction, context);
  EXPECT_NE(line.find("t=12.00 frame=6 now C("), std::string::npos) << line;
  EXPECT_NE(line.find(" | +0.1s C("), std::string::npos) << line;
  EXPECT_NE(line.find(" | +0.2s C("), std::string::npos) << line;
  EXPECT_NE(line.find(" | +0.3s C("), std::string::npos) << line;
  // Robot 3 of the first step: (-4321.25, 1234.567 + 2160.625) rounded, r90 419.6 rounded.
  EXPECT_NE(line.find("[r3 (-4321,3395)? r90=420mm p="), std::string::npos) << line;
  EXPECT_NE(line.find(", r5 (-3210,2840)? r90=420mm p="), std::string::npos) << line;
  EXPECT_NE(line.find("r90=1220mm"), std::string::npos) << line;
  EXPECT_EQ(line.find('\n'), std::string::npos);
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
    const Prediction paper = predict(table, formation, 3);
    // The motion model's robots carry positions and radii; one robot without (radius 0) too.
    Prediction motion = with_motion(paper);
    motion.steps[1].robots[2].radius90_mm = 0.0;
    motion.steps[2].robots[0].feed_position = Point{-1e9, 3e8};
    for (const auto& [model, prediction] :
         {std::pair{ModelKind::paper, paper}, std::pair{ModelKind::motion, motion}})
      for (const AttackDirection side :
           {AttackDirection::positive_x, AttackDirection::negative_x}) {
        PredictionContext context;
        context.model = model;
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
        proto::FormationPrediction decoded;
        ASSERT_TRUE(decoded.ParseFromString(direct));
        EXPECT_EQ(decoded.steps(1).robots(2).has_position(), false);
        EXPECT_EQ(decoded.steps(1).robots(1).has_position(), model == ModelKind::motion);
      }
  }
}

}  // namespace
}  // namespace ssl_formation
