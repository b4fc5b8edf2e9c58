#include "ssl_formation/pipeline/prediction_csv.hpp"

#include <gtest/gtest.h>

#include <charconv>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <string_view>
#include <system_error>
#include <utility>
#include <vector>

#include "ssl_formation/pipeline/training.hpp"
#include "ssl_vision_wrapper.pb.h"

namespace ssl_formation {
namespace {

constexpr std::size_t kColumns = 24;

std::vector<std::string> split(std::string_view text, char separator) {
  std::vector<std::string> parts;
  std::size_t begin = 0;
  while (true) {
    const std::size_t end = text.find(separator, begin);
    parts.emplace_back(text.substr(begin, end - begin));
    if (end == std::string_view::npos) break;
    begin = end + 1;
  }
  return parts;
}

// The lines of `text`, which must end with a newline.
std::vector<std::string> lines_of(const std::string& text) {
  EXPECT_TRUE(text.empty() || text.back() == '\n') << "the last line lacks its newline";
  std::vector<std::string> lines = split(text, '\n');
  lines.pop_back();  // after the last newline
  return lines;
}

// Parses the whole field as a T, exactly as written: a failure leaves the test failing.
template <typename T>
T parse(const std::string& field) {
  T value{};
  const auto [end, error] = std::from_chars(field.data(), field.data() + field.size(), value);
  EXPECT_EQ(error, std::errc()) << "'" << field << "' does not parse";
  EXPECT_EQ(end, field.data() + field.size()) << "'" << field << "' has trailing characters";
  return value;
}

// A cell's centre in the feed's coordinates, computed here from docs/models.md rather than by the
// library: the normalised centre, rotated by 180 degrees for an opponent attacking -x.
Point feed_centre(Cell cell, const Grid& grid, const FieldSize& field, AttackDirection attacks) {
  const double x = (cell.x + 0.5) * field.length_mm / grid.length() - field.length_mm / 2.0;
  const double y = (cell.y + 0.5) * field.width_mm / grid.width() - field.width_mm / 2.0;
  return attacks == AttackDirection::positive_x ? Point{x, y} : Point{-x, -y};
}

// Every line against the formation, prediction and context it was written from.
void check_csv(const std::string& text, const Formation& formation, const Prediction& prediction,
               const PredictionContext& context) {
  const std::vector<std::string> lines = lines_of(text);
  std::size_t expected_lines = 0;
  for (const PredictedStep& step : prediction.steps) expected_lines += step.robots.size();
  ASSERT_EQ(lines.size(), expected_lines) << "one line per robot per step";

  const Grid& grid = context.codec->grid();
  std::size_t line = 0;
  for (std::size_t k = 0; k < prediction.steps.size(); ++k) {
    const PredictedStep& step = prediction.steps[k];
    for (const RobotPrediction& robot : step.robots) {
      SCOPED_TRACE("line " + std::to_string(line) + ": " + lines[line]);
      const std::vector<std::string> c = split(lines[line++], ',');
      ASSERT_EQ(c.size(), kColumns);
      EXPECT_EQ(parse<double>(c[0]), formation.time_s);
      EXPECT_EQ(parse<std::uint32_t>(c[1]), formation.frame_number);
      EXPECT_EQ(parse<std::uint32_t>(c[2]), robot.robot_id);
      EXPECT_EQ(parse<std::size_t>(c[3]), k + 1);
      EXPECT_EQ(parse<double>(c[4]), static_cast<double>(k + 1) * context.step_s);
      EXPECT_EQ(parse<StateIndex>(c[5]), robot.state);
      EXPECT_EQ(parse<int>(c[6]), robot.position.x);
      EXPECT_EQ(parse<int>(c[7]), robot.position.y);
      const Point centre =
          feed_centre(robot.position, grid, context.field, context.opponent_attacks);
      EXPECT_EQ(parse<float>(c[8]), static_cast<float>(centre.x));
      EXPECT_EQ(parse<float>(c[9]), static_cast<float>(centre.y));
      EXPECT_EQ(parse<double>(c[10]), robot.probability);
      EXPECT_EQ(c[11], robot.unseen ? "1" : "0");
      EXPECT_EQ(parse<int>(c[12]), step.centroid.x);
      EXPECT_EQ(parse<int>(c[13]), step.centroid.y);
      EXPECT_EQ(parse<double>(c[14]), step.centroid_probability);
      EXPECT_EQ(parse<double>(c[15]), step.formation_probability);
      EXPECT_EQ(parse<double>(c[16]), step.confidence);
      EXPECT_EQ(c[17], to_string(context.model));
      if (robot.radius90_mm > 0.0) {
        EXPECT_EQ(parse<float>(c[18]), static_cast<float>(robot.feed_position.x));
        EXPECT_EQ(parse<float>(c[19]), static_cast<float>(robot.feed_position.y));
        EXPECT_EQ(parse<float>(c[20]), static_cast<float>(robot.radius50_mm));
        EXPECT_EQ(parse<float>(c[21]), static_cast<float>(robot.radius90_mm));
      } else {
        // The paper's model: the cell's centre again, and no radii.
        EXPECT_EQ(c[18], c[8]);
        EXPECT_EQ(c[19], c[9]);
        EXPECT_EQ(c[20], "0");
        EXPECT_EQ(c[21], "0");
      }
    }
  }
}

TEST(PredictionCsv, Header) {
  const std::string_view header = prediction_csv_header();
  EXPECT_EQ(header,
            "t_capture,frame,robot_id,step,horizon_s,state_index,predicted_cell_x,"
            "predicted_cell_y,predicted_x_mm,predicted_y_mm,probability,unseen,centroid_cell_x,"
            "centroid_cell_y,centroid_probability,formation_probability,confidence,model,"
            "predicted_feed_x_mm,predicted_feed_y_mm,radius_50_mm,radius_90_mm,grid,step_s\n");
  ASSERT_FALSE(header.empty());
  EXPECT_EQ(header.back(), '\n');
  EXPECT_EQ(split(header.substr(0, header.size() - 1), ',').size(), kColumns);
}

// A hand-built prediction whose numbers have no short decimal form, to show they round-trip.
struct HandBuilt {
  StateCodec codec{Grid(3, 2)};
  FormationSample sample;
  Prediction prediction;
  PredictionContext context;

  HandBuilt(AttackDirection attacks, double step_s) {
    context.model = ModelKind::paper;
    sample.formation.time_s = 1700000123.4567891;
    sample.formation.frame_number = 4294967295u;
    sample.formation.robots.resize(2);
    context.codec = &codec;
    context.field = FieldSize{12000.0, 9000.0};
    context.opponent_attacks = attacks;
    context.step_s = step_s;

    const auto robot = [&](std::uint32_t id, Cell centroid, Cell position, Cell previous,
                           double probability, bool unseen) {
      RobotPrediction r;
      r.robot_id = id;
      r.state = codec.encode(RobotState{centroid, position, previous});
      r.position = position;
      r.previous = previous;
      r.probability = probability;
      r.unseen = unseen;
      return r;
    };
    PredictedStep first;
    first.centroid = Cell{2, 1};
    first.centroid_probability = 2.0 / 7.0;
    first.robots = {robot(0, {2, 1}, {0, 0}, {1, 0}, 1.0 / 3.0, false),
                    robot(11, {2, 1}, {2, 1}, {2, 1}, 1.0 / 6.0, true)};
    first.formation_probability = first.centroid_probability / 18.0;
    first.confidence = first.formation_probability;
    PredictedStep second;
    second.centroid = Cell{1, 0};
    second.centroid_probability = 0.1 + 0.2;  // 0.30000000000000004
    second.centroid_unseen = true;
    second.robots = {
        robot(0, {1, 0}, {1, 0}, {0, 0}, std::numeric_limits<double>::denorm_min(), false),
        robot(11, {1, 0}, {2, 0}, {2, 1}, 0.999999999999999, false)};
    second.formation_probability = 1e-300;
    second.confidence = first.confidence * 1e-300;
    prediction.steps = {first, second};
  }
  PredictedFormation predicted() const { return PredictedFormation{sample, prediction, context}; }
};

TEST(PredictionCsv, EveryColumnRoundTripsExactly) {
  const HandBuilt built(AttackDirection::positive_x, 0.1);  // 3 x 0.1 is not 0.3
  std::string text;
  append_prediction_csv(built.predicted(), text);
  check_csv(text, built.sample.formation, built.prediction, built.context);

  // Spot checks against literal values, so that a mistake shared with check_csv shows too.
  const std::vector<std::string> lines = lines_of(text);
  ASSERT_EQ(lines.size(), 4u);
  const std::vector<std::string> first = split(lines[0], ',');
  EXPECT_EQ(first[1], "4294967295");
  EXPECT_EQ(first[2], "0");
  EXPECT_EQ(first[3], "1");
  EXPECT_EQ(first[6], "0");
  EXPECT_EQ(first[7], "0");
  EXPECT_EQ(parse<float>(first[8]), -4000.0F);  // the centre of column 0 of 3 on 12 m
  EXPECT_EQ(parse<float>(first[9]), -2250.0F);  // of row 0 of 2 on 9 m
  EXPECT_EQ(first[11], "0");
  const std::vector<std::string> second = split(lines[1], ',');
  EXPECT_EQ(second[2], "11");
  EXPECT_EQ(second[11], "1");
  const std::vector<std::string> last = split(lines[3], ',');
  EXPECT_EQ(last[3], "2");
  EXPECT_EQ(parse<double>(last[4]), 0.2);
  EXPECT_EQ(parse<double>(split(lines[2], ',')[14]), 0.30000000000000004);
}

TEST(PredictionCsv, TheMotionModelsRowsCarryItsPositionsAndRadii) {
  HandBuilt built(AttackDirection::negative_x, 0.1);
  built.context.model = ModelKind::motion;
  double x = -4321.123456789;
  for (PredictedStep& step : built.prediction.steps) {
    for (RobotPrediction& robot : step.robots) {
      robot.feed_position = Point{x, 1.0 / 3.0 - x};
      robot.radius50_mm = 150.0 + x / 7.0;
      robot.radius90_mm = 2.5 * robot.radius50_mm;
      x += 1234.5678;
    }
  }
  // Still in range and positive: 150 - 4321 / 7 is not, so shift them.
  for (PredictedStep& step : built.prediction.steps) {
    for (RobotPrediction& robot : step.robots) {
      robot.radius50_mm += 1000.0;
      robot.radius90_mm += 2500.0;
    }
  }
  std::string text;
  append_prediction_csv(built.predicted(), text);
  check_csv(text, built.sample.formation, built.prediction, built.context);
  const std::vector<std::string> lines = lines_of(text);
  ASSERT_EQ(lines.size(), 4u);
  const std::vector<std::string> first = split(lines[0], ',');
  ASSERT_EQ(first.size(), kColumns);
  EXPECT_EQ(first[17], "motion");
  EXPECT_EQ(parse<float>(first[18]), static_cast<float>(-4321.123456789));
  EXPECT_EQ(parse<float>(first[19]), static_cast<float>(1.0 / 3.0 + 4321.123456789));
  EXPECT_EQ(parse<float>(first[20]), static_cast<float>(150.0 - 4321.123456789 / 7.0 + 1000.0));
  EXPECT_EQ(parse<float>(first[21]),
            static_cast<float>(2.5 * (150.0 - 4321.123456789 / 7.0) + 2500.0));
  // The cell columns stay the cell's: the centre of normalised (0, 0), rotated back.
  EXPECT_EQ(parse<float>(first[8]), 4000.0F);
  EXPECT_EQ(parse<float>(first[9]), 2250.0F);
}

TEST(PredictionCsv, ThePaperModelsRowsRepeatTheCellCentreWithRadiiZero) {
  const HandBuilt built(AttackDirection::positive_x, 2.0);
  std::string text;
  append_prediction_csv(built.predicted(), text);
  const std::vector<std::string> first = split(lines_of(text)[0], ',');
  ASSERT_EQ(first.size(), kColumns);
  EXPECT_EQ(first[17], "paper");
  EXPECT_EQ(first[18], "-4000");
  EXPECT_EQ(first[19], "-2250");
  EXPECT_EQ(first[20], "0");
  EXPECT_EQ(first[21], "0");
}

TEST(PredictionCsv, HorizonSecondsAreTheStepTimesTheSamplingStep) {
  HandBuilt built(AttackDirection::positive_x, 0.1);
  built.prediction.steps.resize(3, built.prediction.steps[1]);
  std::string text;
  append_prediction_csv(built.predicted(), text);
  const std::vector<std::string> lines = lines_of(text);
  ASSERT_EQ(lines.size(), 6u);
  EXPECT_EQ(parse<double>(split(lines[0], ',')[4]), 0.1);
  EXPECT_EQ(parse<double>(split(lines[2], ',')[4]), 0.2);
  EXPECT_EQ(parse<double>(split(lines[4], ',')[4]), 3 * 0.1);
  EXPECT_NE(parse<double>(split(lines[4], ',')[4]), 0.3);
}

TEST(PredictionCsv, AnOpponentAttackingMinusXIsRotatedBackToTheFeed) {
  const HandBuilt plus(AttackDirection::positive_x, 2.0);
  const HandBuilt minus(AttackDirection::negative_x, 2.0);
  std::string plus_text;
  std::string minus_text;
  append_prediction_csv(plus.predicted(), plus_text);
  append_prediction_csv(minus.predicted(), minus_text);
  check_csv(minus_text, minus.sample.formation, minus.prediction, minus.context);
  const std::vector<std::string> plus_lines = lines_of(plus_text);
  const std::vector<std::string> minus_lines = lines_of(minus_text);
  ASSERT_EQ(plus_lines.size(), minus_lines.size());
  for (std::size_t i = 0; i < plus_lines.size(); ++i) {
    const auto p = split(plus_lines[i], ',');
    const auto m = split(minus_lines[i], ',');
    // The cells are the model's (normalised) and stay; the millimetres are the feed's.
    EXPECT_EQ(m[6], p[6]);
    EXPECT_EQ(m[7], p[7]);
    EXPECT_EQ(parse<float>(m[8]), -parse<float>(p[8])) << "line " << i;
    EXPECT_EQ(parse<float>(m[9]), -parse<float>(p[9])) << "line " << i;
  }
  // Robot 0 of the first step, in normalised cell (0, 0): at +x (-4000, -2250) in the feed.
  EXPECT_EQ(parse<float>(split(minus_lines[0], ',')[8]), 4000.0F);
  EXPECT_EQ(parse<float>(split(minus_lines[0], ',')[9]), 2250.0F);
}

TEST(PredictionCsv, AppendsAndWritesNothingForAnEmptyPrediction) {
  HandBuilt built(AttackDirection::positive_x, 2.0);
  std::string text = "kept\n";
  append_prediction_csv(built.predicted(), text);
  ASSERT_EQ(text.rfind("kept\n", 0), 0u);
  check_csv(text.substr(5), built.sample.formation, built.prediction, built.context);

  built.prediction.steps.clear();
  std::string empty;
  append_prediction_csv(built.predicted(), empty);
  EXPECT_EQ(empty, "");
}

// ---- Through the real pipeline ----

SSL_WrapperPacket detection(double t_capture, std::uint32_t frame_number,
                            const std::vector<std::pair<std::uint32_t, Point>>& robots) {
  SSL_WrapperPacket packet;
  SSL_DetectionFrame& frame = *packet.mutable_detection();
  frame.set_frame_number(frame_number);
  frame.set_t_capture(t_capture);
  frame.set_t_sent(t_capture);
  frame.set_camera_id(0);
  for (const auto& [id, at] : robots) {
    SSL_DetectionRobot& r = *frame.add_robots_yellow();
    r.set_confidence(1.0F);
    r.set_robot_id(id);
    r.set_x(static_cast<float>(at.x));
    r.set_y(static_cast<float>(at.y));
    r.set_pixel_x(0.0F);
    r.set_pixel_y(0.0F);
  }
  return packet;
}

// Robots walking around a 9 x 6 m field, one frame per sampling step.
std::vector<std::pair<std::uint32_t, Point>> walk(int k) {
  static const double xs[4] = {-4000.0, -500.0, 2000.0, 4200.0};
  return {{2, {xs[k % 4], -2000.0}}, {5, {-xs[(k + 1) % 4], 2500.0}}, {9, {100.0, 0.0}}};
}

TEST(PredictionCsv, TheLinesOfThePipelineMatchWhatItPredicted) {
  for (AttackDirection attacks : {AttackDirection::positive_x, AttackDirection::negative_x}) {
    SCOPED_TRACE(std::string(to_string(attacks)));
    SamplerConfig config;
    config.grid = Grid(3, 2);
    config.step_s = 0.7;
    config.opponent_attacks = attacks;
    Training training(config, TransitionTable(config.grid));
    for (int k = 0; k < 40; ++k) {
      training.add(detection(100.0 + 0.7 * k, static_cast<std::uint32_t>(k), walk(k)));
    }
    ASSERT_GT(training.stored_table().table.transitions(), 0u);
    const auto table = std::make_shared<const StoredTable>(
        StoredTable{training.stored_table().table, {}, nullptr});

    struct Seen {
      std::string csv;
      Formation formation;
      Prediction prediction;
      PredictionContext context;
    };
    std::vector<Seen> seen;
    PredictionPipeline pipeline(PredictionConfig{config, 3, ModelKind::paper},
                                [&](const PredictedFormation& p) {
                                  Seen s{std::string(), p.formation(), p.prediction, p.context};
                                  append_prediction_csv(p, s.csv);
                                  seen.push_back(std::move(s));
                                });
    pipeline.set_table(table);
    for (int k = 0; k < 10; ++k) {
      pipeline.add(detection(1234.56789 + 0.7 * k, static_cast<std::uint32_t>(500 + k), walk(k)));
    }
    ASSERT_GE(seen.size(), 9u);
    for (const Seen& s : seen) {
      ASSERT_EQ(s.prediction.steps.size(), 3u);
      check_csv(s.csv, s.formation, s.prediction, s.context);
    }
  }
}

// Robots circling at a few metres a second, seen at 60 Hz.
std::vector<std::pair<std::uint32_t, Point>> circling(double t) {
  std::vector<std::pair<std::uint32_t, Point>> robots;
  for (std::uint32_t id = 0; id < 3; ++id) {
    const double phase = 0.8 * t + 2.0 * id;
    robots.push_back({id, {2500.0 * std::cos(phase), 1800.0 * std::sin(phase)}});
  }
  return robots;
}

TEST(PredictionCsv, TheMotionModelsLinesOfThePipelineCarryItsPositionsAndRadii) {
  SamplerConfig config;
  config.grid = Grid(3, 2);
  config.step_s = 0.5;
  config.sampling = Sampling::frame;
  MotionConfig motion;
  motion.step_s = config.step_s;
  Training training(config, TransitionTable(config.grid), 0, MotionTable(motion));
  for (int k = 0; k < 60 * 60; ++k) {
    training.add(detection(100.0 + k / 60.0, static_cast<std::uint32_t>(k), circling(k / 60.0)));
  }
  ASSERT_NE(training.stored_table().motion, nullptr);
  ASSERT_GT(training.stored_table().motion->instances(), 0u);
  const auto table = std::make_shared<const StoredTable>(training.stored_table(TableMetadata{}));

  std::vector<std::string> csv;
  std::size_t checked = 0;
  PredictionPipeline pipeline(PredictionConfig{config, 2, ModelKind::motion},
                              [&](const PredictedFormation& p) {
                                std::string text;
                                append_prediction_csv(p, text);
                                check_csv(text, p.formation(), p.prediction, p.context);
                                csv.push_back(std::move(text));
                                ++checked;
                              });
  pipeline.set_table(table);
  for (int k = 0; k < 120; ++k) {
    pipeline.add(detection(500.0 + k / 60.0, static_cast<std::uint32_t>(9000 + k),
                           circling(500.0 + k / 60.0)));
  }
  ASSERT_GE(checked, 60u);
  // Every line is the motion model's, with a position and radii 0 < r50 < r90.
  for (const std::string& text : csv) {
    for (const std::string& line : lines_of(text)) {
      const std::vector<std::string> c = split(line, ',');
      ASSERT_EQ(c.size(), kColumns);
      EXPECT_EQ(c[17], "motion");
      const float r50 = parse<float>(c[20]);
      const float r90 = parse<float>(c[21]);
      EXPECT_GT(r50, 0.0F) << line;
      EXPECT_GT(r90, r50) << line;
    }
  }
}

}  // namespace
}  // namespace ssl_formation

namespace ssl_formation {
namespace {

TEST(PredictionCsvReader, ReadsBackWhatThePredictorWrites) {
  HandBuilt built(AttackDirection::negative_x, 0.5);
  built.context.model = ModelKind::motion;
  double x = -4321.123456789;
  for (PredictedStep& step : built.prediction.steps) {
    for (RobotPrediction& robot : step.robots) {
      robot.feed_position = Point{x, 1.0 / 3.0 - x};
      robot.radius50_mm = 1150.0;
      robot.radius90_mm = 2500.0 + x / 10.0;
      x += 1234.5678;
    }
  }
  std::string text(prediction_csv_header());
  append_prediction_csv(built.predicted(), text);
  const Result<RecordedPredictions> read = parse_prediction_csv(text, "p.csv");
  ASSERT_TRUE(read) << read.error().message;
  ASSERT_EQ(read->instants.size(), 1u);
  EXPECT_EQ(read->instants[0].time_s, built.sample.formation.time_s);
  EXPECT_DOUBLE_EQ(read->step_s, 0.5);
  EXPECT_EQ(read->steps, static_cast<int>(built.prediction.steps.size()));
  EXPECT_TRUE(read->has_radii);
  EXPECT_TRUE(read->has_cells);
  const Prediction& back = read->instants[0].prediction;
  ASSERT_EQ(back.steps.size(), built.prediction.steps.size());
  for (std::size_t k = 0; k < back.steps.size(); ++k) {
    const PredictedStep& want = built.prediction.steps[k];
    ASSERT_EQ(back.steps[k].robots.size(), want.robots.size());
    EXPECT_EQ(back.steps[k].formation_probability, want.formation_probability);
    for (std::size_t r = 0; r < want.robots.size(); ++r) {
      const RobotPrediction& a = back.steps[k].robots[r];
      const RobotPrediction& b = want.robots[r];
      EXPECT_EQ(a.robot_id, b.robot_id);
      // Read as written: the message's float, to the last digit.
      EXPECT_EQ(static_cast<float>(a.feed_position.x), static_cast<float>(b.feed_position.x));
      EXPECT_EQ(static_cast<float>(a.feed_position.y), static_cast<float>(b.feed_position.y));
      EXPECT_EQ(static_cast<float>(a.radius90_mm), static_cast<float>(b.radius90_mm));
      EXPECT_NEAR(a.feed_position.x, b.feed_position.x, 1e-3);
      EXPECT_EQ(a.position, b.position);
      EXPECT_EQ(a.state, b.state);
      EXPECT_EQ(a.probability, b.probability);
    }
  }
}

TEST(PredictionCsvReader, TakesTheKeyColumnsInAnyOrderAndGroupsByInstantAndStep) {
  // A team's own file: five columns, shuffled, lines out of order, no step column.
  const std::string text =
      "robot_id,predicted_feed_y_mm,horizon_s,t_capture,predicted_feed_x_mm\r\n"
      "3,20,1.0,2.5,10\r\n"
      "3,21,0.5,2.5,11\n"
      "4,30,0.5,1.25,-5\n"
      "\n"
      "5,31,0.5,2.5,-6\n";
  const Result<RecordedPredictions> read = parse_prediction_csv(text, "team.csv");
  ASSERT_TRUE(read) << read.error().message;
  EXPECT_DOUBLE_EQ(read->step_s, 0.5);
  EXPECT_EQ(read->steps, 2);
  EXPECT_FALSE(read->has_radii);
  EXPECT_FALSE(read->has_cells);
  ASSERT_EQ(read->instants.size(), 2u);
  EXPECT_EQ(read->instants[0].time_s, 1.25);
  ASSERT_EQ(read->instants[0].prediction.steps.size(), 1u);
  EXPECT_EQ(read->instants[0].prediction.steps[0].robots[0].robot_id, 4u);
  const Prediction& later = read->instants[1].prediction;
  ASSERT_EQ(later.steps.size(), 2u);
  ASSERT_EQ(later.steps[0].robots.size(), 2u);  // robots 3 and 5 at 0.5 s
  EXPECT_EQ(later.steps[0].robots[0].feed_position.x, 11.0);
  ASSERT_EQ(later.steps[1].robots.size(), 1u);  // robot 3 at 1 s
  EXPECT_EQ(later.steps[1].robots[0].feed_position.y, 20.0);
}

TEST(PredictionCsvReader, BadInputNamesTheFileTheLineAndTheColumn) {
  const auto error = [](const std::string& text) {
    const Result<RecordedPredictions> read = parse_prediction_csv(text, "p.csv");
    return read ? std::string("no error") : read.error().message;
  };
  EXPECT_NE(error("t_capture,robot_id,horizon_s,predicted_feed_x_mm\n1,2,0.5,3\n")
                .find("no column 'predicted_feed_y_mm'"),
            std::string::npos);
  const std::string header =
      "t_capture,robot_id,horizon_s,predicted_feed_x_mm,predicted_feed_y_mm\n";
  EXPECT_NE(error(header + "1,2,0.5,3,4\n1,2,0.5,x,4\n")
                .find("p.csv:3: column 'predicted_feed_x_mm' holds 'x'"),
            std::string::npos)
      << error(header + "1,2,0.5,3,4\n1,2,0.5,x,4\n");
  EXPECT_NE(error(header + "1,2,0.5,3\n").find("p.csv:2: 4 fields where the header has 5"),
            std::string::npos);
  EXPECT_NE(error(header + "1,2,0.5,3,4\n1,2,0.75,3,4\n").find("not a whole number of steps"),
            std::string::npos);
  EXPECT_NE(error(header + "1,2,0,3,4\n").find("column 'horizon_s'"), std::string::npos);
  EXPECT_NE(error(header).find("no predictions"), std::string::npos);
  EXPECT_FALSE(read_prediction_csv("/nonexistent/p.csv"));
}

}  // namespace
}  // namespace ssl_formation
