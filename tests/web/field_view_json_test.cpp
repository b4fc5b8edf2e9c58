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
  const std::string json = prediction_json(sample_message(), setup, ours);
  EXPECT_TRUE(json.starts_with(R"({"type":"prediction","frame":61,"t":122,)")) << json;
  EXPECT_NE(json.find(R"("field":{"length":9000,"width":6000},"grid":{"length":3,"width":2})"),
            std::string::npos)
      << json;
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
  const std::string json = prediction_json(m, FieldViewSetup{}, {});
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
  const std::string json = prediction_json(m, FieldViewSetup{}, {});
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
  EXPECT_NE(
      json.find(R"("packets":1234,"packets_per_s":40.5,"since_packet_s":null,)"
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
                R"("match":{"opponent":"","game_state":"unknown","referee":"no referee heard"})"),
            std::string::npos)
      << status_json(status);
  status.opponent = "'Them' blue (referee), attacks -x (referee)";
  status.game_state = "ball_placement";
  status.referee = "game ball_placement, yellow 'Us', blue 'Them'";
  EXPECT_NE(status_json(status).find(
                R"j("match":{"opponent":"'Them' blue (referee), attacks -x (referee)",)j"
                R"j("game_state":"ball_placement","referee":"game ball_placement, yellow 'Us', )j"
                R"j(blue 'Them'"})j"),
            std::string::npos)
      << status_json(status);
}

TEST(FieldViewJson, TheAgeOfTheLastPacketIsTheServersOwnAndNeverNegative) {
  FieldViewStatus status;
  status.since_packet_s = 0.25;
  status.last_packet_unix_ms = 1700000000000;
  status.server_unix_ms = 1700000000250;
  EXPECT_NE(status_json(status).find(
                R"("since_packet_s":0.25,"last_packet_unix_ms":1700000000000,)"
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
