#include "field_view_json.hpp"

#include <gtest/gtest.h>

namespace ssl_formation::predictor::web {
namespace {

proto::FormationPrediction sample_message() {
  proto::FormationPrediction m;
  m.set_frame_number(61);
  m.set_t_capture(122.0);
  m.mutable_centroid_cell()->set_x(1);
  m.mutable_centroid_cell()->set_y(0);
  proto::CurrentRobot& r = *m.add_robots();
  r.set_robot_id(4);
  r.set_state_index(17);
  r.mutable_position_cell()->set_x(2);
  r.mutable_position_cell()->set_y(1);
  r.mutable_previous_cell()->set_x(2);
  r.mutable_previous_cell()->set_y(1);
  r.mutable_position()->set_x(-2500.0f);
  r.mutable_position()->set_y(-1000.0f);
  proto::PredictedStep& s = *m.add_steps();
  s.set_step(1);
  s.mutable_centroid_cell()->set_x(2);
  s.mutable_centroid_cell()->set_y(1);
  s.set_centroid_probability(0.5);
  s.set_centroid_unseen(false);
  s.set_formation_probability(0.25);
  s.set_confidence(0.125);
  proto::PredictedRobot& p = *s.add_robots();
  p.set_robot_id(4);
  p.set_state_index(18);
  p.mutable_position_cell()->set_x(2);
  p.mutable_position_cell()->set_y(1);
  p.mutable_previous_cell()->set_x(2);
  p.mutable_previous_cell()->set_y(1);
  p.mutable_cell_centre()->set_x(-3000.0f);
  p.mutable_cell_centre()->set_y(-1500.0f);
  p.set_probability(1.0);
  p.set_unseen(true);
  m.set_table_transitions(9000);
  m.set_step_seconds(2.0);
  return m;
}

TEST(FieldViewJson, PredictionCarriesFieldGridRobotsAndStepsInFeedCoordinates) {
  FieldViewSetup setup;
  setup.opponent_attacks = AttackDirection::negative_x;
  setup.opponent_color = TeamColor::blue;
  const std::vector<TeamRobot> ours{{0, 1000.0, 250.5, 3.0}};
  const std::string json = prediction_json(sample_message(), setup, ours, BallTrail{});
  EXPECT_TRUE(json.starts_with(R"({"type":"prediction","frame":61,"t":122,)")) << json;
  EXPECT_NE(json.find(R"("field":{"length":9000,"width":6000,"markings":{"goal_width":1000,)"
                      R"("goal_depth":180,"boundary_width":300,"penalty_area_depth":1000,)"
                      R"("penalty_area_width":2000,"center_circle_radius":500,"source":"rules"}},)"
                      R"("grid":{"length":3,"width":2})"),
            std::string::npos)
      << json;
  EXPECT_NE(json.find(R"("ball":null,"steps")"), std::string::npos) << json;
  EXPECT_NE(json.find(R"("opponent_color":"blue","our_color":"yellow","opponent_attacks":"-x")"),
            std::string::npos);
  // Cell (1,0) of an opponent attacking -x: centre (0,-1500) rotated by 180 degrees.
  EXPECT_NE(json.find(R"("centroid":{"cell":[1,0],"centre":[0,1500]})"), std::string::npos) << json;
  EXPECT_NE(json.find(R"("opponent":[{"id":4,"x":-2500,"y":-1000,"cell":[2,1]}])"),
            std::string::npos)
      << json;
  EXPECT_NE(json.find(R"("ours":[{"id":0,"x":1000,"y":250.5}])"), std::string::npos) << json;
  EXPECT_NE(
      json.find(
          R"("steps":[{"step":1,"horizon_s":2,"centroid":{"cell":[2,1],"centre":[-3000,-1500]},)"
          R"("centroid_p":0.5,)"
          R"("centroid_unseen":false,"formation_p":0.25,"confidence":0.125,)"
          R"("robots":[{"id":4,"cell":[2,1],"centre":[-3000,-1500],"p":1,"unseen":true}]}])"),
      std::string::npos)
      << json;
  EXPECT_TRUE(json.ends_with("]}"));
  // A message without a model (an older predictor) is the paper's; its robots state no position.
  EXPECT_NE(json.find(R"("model":"paper")"), std::string::npos) << json;
  EXPECT_EQ(json.find(R"("position")"), std::string::npos) << json;
  EXPECT_EQ(json.find(R"("radius_90_mm")"), std::string::npos) << json;
}

TEST(FieldViewJson, TheMotionModelsRobotsCarryPositionsAndRadiiAndStepsTheirHorizons) {
  proto::FormationPrediction m = sample_message();
  m.set_model("motion");
  m.set_step_seconds(0.1);
  proto::PredictedStep& first = *m.mutable_steps(0);
  first.set_horizon_seconds(0.1);
  proto::PredictedRobot& robot = *first.mutable_robots(0);
  robot.mutable_position()->set_x(-2750.5F);
  robot.mutable_position()->set_y(1234.0F);
  robot.set_radius_50_mm(150.25F);
  robot.set_radius_90_mm(420.0F);
  proto::PredictedStep& second = *m.add_steps();
  second = first;
  second.set_step(2);
  second.set_horizon_seconds(2 * 0.1);
  second.mutable_robots(0)->set_radius_90_mm(900.0F);
  const std::string json = prediction_json(m, FieldViewSetup{}, {}, BallTrail{});
  EXPECT_NE(json.find(R"("model":"motion")"), std::string::npos) << json;
  EXPECT_NE(json.find(R"({"step":1,"horizon_s":0.1,)"), std::string::npos) << json;
  EXPECT_NE(json.find(R"({"step":2,"horizon_s":0.2,)"), std::string::npos) << json;
  EXPECT_NE(
      json.find(R"("robots":[{"id":4,"cell":[2,1],"centre":[-3000,-1500],"p":1,"unseen":true,)"
                R"("position":[-2750.5,1234],"radius_50_mm":150.25,"radius_90_mm":420}])"),
      std::string::npos)
      << json;
  EXPECT_NE(json.find(R"("radius_90_mm":900})"), std::string::npos) << json;
}

TEST(FieldViewJson, AStepWithoutItsHorizonIsTheStepTimesTheStepSeconds) {
  proto::FormationPrediction m = sample_message();
  m.set_step_seconds(0.25);
  *m.add_steps() = m.steps(0);
  m.mutable_steps(1)->set_step(2);
  const std::string json = prediction_json(m, FieldViewSetup{}, {}, BallTrail{});
  EXPECT_NE(json.find(R"({"step":1,"horizon_s":0.25,)"), std::string::npos) << json;
  EXPECT_NE(json.find(R"({"step":2,"horizon_s":0.5,)"), std::string::npos) << json;
}

TEST(FieldViewJson, StatusCarriesTheStreamAndTheTable) {
  FieldViewStatus status;
  status.packets = 1234;
  status.packets_per_s = 40.5;
  status.parse_errors = 2;
  status.table_loaded = true;
  status.table_transitions = 9000;
  status.table_formations = 1500;
  status.table_reloads = 3;
  status.table_loaded_unix_ms = 1700000000123;
  status.table_error = "bad \"file\"";
  const std::string json = status_json(status);
  EXPECT_NE(json.find(R"("packets":1234,"packets_per_s":40.5,"since_packet_s":null,)"
                      R"("last_packet_unix_ms":null,"server_unix_ms":null,"parse_errors":2)"),
            std::string::npos)
      << json;
  EXPECT_NE(
      json.find(
          R"("table":{"loaded":true,"transitions":9000,"formations":1500,"motion_instances":null,)"
          R"("states_seen":0,"reloads":3,)"
          R"("loaded_unix_ms":1700000000123,"error":"bad \"file\""})"),
      std::string::npos)
      << json;
  EXPECT_NE(json.find(R"("ours":[])"), std::string::npos);
  status.since_packet_s = 3.25;
  EXPECT_NE(status_json(status).find(R"("since_packet_s":3.25)"), std::string::npos);
}

TEST(FieldViewJson, StatusSaysWhoTheOpponentIsWhyAndTheGameState) {
  FieldViewStatus status;
  EXPECT_NE(status_json(status).find(
                R"("match":{"opponent":"","game_state":"unknown","phase":"running",)"
                R"("referee":"no referee heard","heard":false,"stage":null,"for_team":null,)"
                R"("yellow":"","blue":"","designated_position":null})"),
            std::string::npos)
      << status_json(status);
  status.opponent = "'Them' blue (referee), attacks -x (referee)";
  status.setup.opponent_color = TeamColor::blue;
  status.game_state = "ball_placement";
  status.phase = GamePhase::ball_placement_opponent;
  status.referee = "game ball_placement, yellow 'Us', blue 'Them'";
  status.referee_heard = true;
  status.referee_view.state = GameState::ball_placement;
  status.referee_view.command = 17;  // BALL_PLACEMENT_BLUE
  status.referee_view.stage = 1;     // NORMAL_FIRST_HALF
  status.referee_view.yellow_name = "Us";
  status.referee_view.blue_name = "Them";
  status.referee_view.designated_position = Point{-1500.0, 250.0};
  EXPECT_NE(status_json(status).find(
                R"j("match":{"opponent":"'Them' blue (referee), attacks -x (referee)",)j"
                R"j("game_state":"ball_placement","phase":"ball_placement_opponent",)j"
                R"j("referee":"game ball_placement, yellow 'Us', blue 'Them'","heard":true,)j"
                R"j("stage":"NORMAL_FIRST_HALF","for_team":"opponent","yellow":"Us",)j"
                R"j("blue":"Them","designated_position":[-1500,250]})j"),
            std::string::npos)
      << status_json(status);
  // Yellow's placement is ours when the opponent is blue.
  status.referee_view.command = 16;  // BALL_PLACEMENT_YELLOW
  EXPECT_NE(status_json(status).find(R"("for_team":"us")"), std::string::npos);
  // HALT is nobody's.
  status.referee_view.command = 0;
  EXPECT_NE(status_json(status).find(R"("for_team":null)"), std::string::npos);
}

TEST(FieldViewJson, StatusCarriesTheBallItsPathAndTheLateFiguresByPhase) {
  FieldViewStatus status;
  BallTrail ball;
  ball.update(BallState{10.0, Point{100.0, 200.0}, Point{}}, 10.0);
  ball.update(BallState{10.1, Point{150.0, 200.0}, Point{}}, 10.1);
  status.ball = &ball;
  status.live_score = {LiveScore::Horizon{0.5, 40.0, 90.0, 12.0}};
  status.live_score_by_phase = {
      PhaseLiveScore{GamePhase::stop, {LiveScore::Horizon{0.5, 30.0, 20.0, 4.0}}},
      PhaseLiveScore{GamePhase::free_kick_us, {LiveScore::Horizon{0.5, 45.0, 125.0, 8.0}}}};
  const std::string json = status_json(status);
  EXPECT_NE(json.find(R"("ball":{"x":150,"y":200,"path":[[100,200],[150,200]]})"),
            std::string::npos)
      << json;
  EXPECT_NE(json.find(R"("live_score":[{"horizon_s":0.5,"model_mm":40,"persistence_mm":90,)"
                      R"("robots":12}],"live_score_by_phase":[{"phase":"stop","horizons":)"
                      R"([{"horizon_s":0.5,"model_mm":30,"persistence_mm":20,"robots":4}]},)"
                      R"({"phase":"free_kick_us","horizons":[{"horizon_s":0.5,"model_mm":45,)"
                      R"("persistence_mm":125,"robots":8}]}]})"),
            std::string::npos)
      << json;
  // A ball gone for longer than the trail keeps it: null.
  ball.update(BallState{10.1, Point{150.0, 200.0}, Point{}}, 11.0);
  EXPECT_NE(status_json(status).find(R"("ball":null)"), std::string::npos);
}

TEST(FieldViewJson, MarkingsComeFromTheGeometryWhereTheyFitTheField) {
  const FieldSize division_a{12000.0, 9000.0};
  const ViewMarkings rules_a = markings_for(division_a, std::nullopt);
  EXPECT_EQ(rules_a.goal_width_mm, 1800.0);
  EXPECT_EQ(rules_a.penalty_area_width_mm, 3600.0);
  EXPECT_EQ(rules_a.penalty_area_depth_mm, 1800.0);
  EXPECT_EQ(rules_a.source, "rules");
  const ViewMarkings rules_b = markings_for(FieldSize{9000.0, 6000.0}, std::nullopt);
  EXPECT_EQ(rules_b.goal_width_mm, 1000.0);
  EXPECT_EQ(rules_b.penalty_area_depth_mm, 1000.0);
  // A packet stating all of them, differently from the rules.
  const ViewMarkings stated =
      markings_for(division_a, FieldMarkings{1600, 200, 250, 1500, 3000, 600});
  EXPECT_EQ(stated.goal_width_mm, 1600.0);
  EXPECT_EQ(stated.goal_depth_mm, 200.0);
  EXPECT_EQ(stated.boundary_width_mm, 250.0);
  EXPECT_EQ(stated.penalty_area_depth_mm, 1500.0);
  EXPECT_EQ(stated.penalty_area_width_mm, 3000.0);
  EXPECT_EQ(stated.center_circle_radius_mm, 600.0);
  EXPECT_EQ(stated.source, "geometry");
  // An older sender leaves the penalty area out, and a goal wider than the field is nonsense:
  // the rules' values stand in for both.
  const ViewMarkings partly = markings_for(division_a, FieldMarkings{20000, 180, 300, 0, 0, 500});
  EXPECT_EQ(partly.goal_width_mm, 1800.0);
  EXPECT_EQ(partly.penalty_area_depth_mm, 1800.0);
  EXPECT_EQ(partly.penalty_area_width_mm, 3600.0);
  EXPECT_EQ(partly.source, "geometry and rules");
}

TEST(FieldViewJson, TheAgeOfTheLastPacketIsTheServersOwnAndNeverNegative) {
  FieldViewStatus status;
  status.since_packet_s = 0.25;
  status.last_packet_unix_ms = 1700000000000;
  status.server_unix_ms = 1700000000250;
  EXPECT_NE(status_json(status).find(R"("since_packet_s":0.25,"last_packet_unix_ms":1700000000000,)"
                                     R"("server_unix_ms":1700000000250,)"),
            std::string::npos)
      << status_json(status);
  // Two clock reads racing each other: a hair below zero is written as zero.
  status.since_packet_s = -1e-7;
  EXPECT_NE(status_json(status).find(R"("since_packet_s":0,)"), std::string::npos)
      << status_json(status);
}

TEST(FieldViewJson, StatusCarriesTheTablesFormationsAndMotionInstances) {
  FieldViewStatus status;
  status.table_loaded = true;
  status.table_transitions = 12;
  status.table_formations = 34567;
  status.table_motion_instances = 890123;
  const std::string json = status_json(status);
  EXPECT_NE(json.find(R"("table":{"loaded":true,"transitions":12,"formations":34567,)"
                      R"("motion_instances":890123,)"),
            std::string::npos)
      << json;
}

}  // namespace
}  // namespace ssl_formation::predictor::web
