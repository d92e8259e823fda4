// Tracker CSV: round trip, and malformed input reported with line numbers.
#include <doctest/doctest.h>

#include <sstream>

#include "sparsebody/recordings/tracker_csv.hpp"

using namespace sparsebody;

namespace {
std::vector<trackers::TrackerFrame> sample() {
  std::vector<trackers::TrackerFrame> v(3);
  for (int i = 0; i < 3; ++i) {
    v[i].time = 0.0111 * i;
    for (int k = 0; k < 4; ++k) {
      v[i].pose[k].position = {0.1f * k, 1.0f + 0.01f * i, -0.5f};
      v[i].pose[k].orientation = {0.0f, 0.70710677f, 0.0f, 0.70710677f};
      v[i].valid[k] = !(i == 1 && k == 2);
    }
  }
  return v;
}

std::string error_of(const std::string& s) {
  std::istringstream in(s);
  try {
    recordings::parse_tracker_csv(in, "session.csv");
  } catch (const LoadError& e) {
    return e.what();
  }
  return "";
}
}  // namespace

TEST_CASE("tracker CSV round trip") {
  std::ostringstream out;
  recordings::write_tracker_csv(out, sample(), "test");
  std::istringstream in(out.str());
  const auto back = recordings::parse_tracker_csv(in, "x.csv");
  REQUIRE(back.size() == 3);
  CHECK(back[2].time == doctest::Approx(0.0222));
  CHECK(back[1].pose[3].position.x == doctest::Approx(0.3f));
  CHECK(back[0].pose[0].orientation.y == doctest::Approx(0.70710677f));
  CHECK_FALSE(back[1].valid[2]);
  CHECK(back[1].valid[1]);
}

TEST_CASE("tracker CSV errors name the line and the field") {
  std::ostringstream out;
  recordings::write_tracker_csv(out, sample());
  const std::string good = out.str();  // lines: 1 comment, 2 header, 3..5 rows
  auto with_row3 = [&](const std::string& row) {
    std::string s = good;
    const auto a = s.find('\n', s.find("pelvis_valid")) + 1;
    const auto b = s.find('\n', a);
    return s.replace(a, b - a, row);
  };
  CHECK(error_of(with_row3("0,1,2")) == "session.csv: line 3: expected 33 comma-separated fields, got 3");
  std::string row = "0";
  for (int i = 0; i < 32; ++i) row += i == 3 ? ",abc" : ",1";
  CHECK(error_of(with_row3(row)) == "session.csv: line 3: field 'head_qx': expected a number, got 'abc'");
  row = "0";
  for (int i = 0; i < 32; ++i) row += i == 7 ? ",2" : ",1";
  CHECK(error_of(with_row3(row)) == "session.csv: line 3: field 'head_valid': expected 0 or 1");
  row = "nan";
  for (int i = 0; i < 32; ++i) row += ",1";
  CHECK(error_of(with_row3(row)) == "session.csv: line 3: field 'time': expected a finite number of seconds");
  CHECK(error_of("time,x\n").find("line 1: expected the header") != std::string::npos);
  CHECK(error_of("# only a comment\n").find("line 1: expected the header line") != std::string::npos);
  // times are kept as recorded, also where they repeat or go back (a replay must be exact)
  {
    std::string row1 = "0.5", row2 = "0.5", row3 = "0.25";
    for (int i = 0; i < 32; ++i) row1 += ",1", row2 += ",1", row3 += ",1";
    std::istringstream in(recordings::tracker_csv_header() + "\n" + row1 + "\n" + row2 + "\n" + row3 + "\n");
    const auto v = recordings::parse_tracker_csv(in, "glitch.csv");
    REQUIRE(v.size() == 3);
    CHECK(v[1].time == 0.5);
    CHECK(v[2].time == 0.25);
  }
  // nan pose values are accepted by the reader (the pipeline sanitizes them)
  row = "0.5";
  for (int i = 0; i < 32; ++i) row += i == 0 ? ",nan" : ",1";
  std::string s = good + row + "\n";
  std::istringstream in(s);
  const auto v = recordings::parse_tracker_csv(in, "x.csv");
  CHECK(std::isnan(v.back().pose[0].position.x));
}
