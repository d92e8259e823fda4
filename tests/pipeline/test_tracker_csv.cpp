// Tracker CSV: round trip, and malformed input reported with line numbers.
#include <doctest/doctest.h>

#include <iomanip>
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

TEST_CASE("tracker CSV as recorders write it: columns in any order, no pelvis columns, time in ms / us / ns") {
  const auto want = sample();
  std::ostringstream out;
  recordings::write_tracker_csv(out, want);
  // the columns reversed and the pelvis's left out
  std::vector<std::string> header, rows[3];
  {
    std::istringstream in(out.str());
    std::string line;
    int r = -1;
    while (std::getline(in, line)) {
      if (line.empty() || line[0] == '#') continue;
      std::vector<std::string> cells;
      std::stringstream ls(line);
      std::string c;
      while (std::getline(ls, c, ',')) cells.push_back(c);
      cells.resize(cells.size() - 8);  // no pelvis
      (r < 0 ? header : rows[r]) = std::vector<std::string>(cells.rbegin(), cells.rend());
      ++r;
    }
  }
  auto join = [](const std::vector<std::string>& v) {
    std::string s;
    for (const auto& c : v) s += (s.empty() ? "" : ",") + c;
    return s + "\n";
  };
  std::string csv = join(header);
  for (const auto& r : rows) csv += join(r);
  std::istringstream in(csv);
  recordings::TrackerCsvInfo info;
  const auto got = recordings::parse_tracker_csv(in, "reordered.csv", &info);
  REQUIRE(got.size() == want.size());
  CHECK_FALSE(info.pelvis_columns);
  CHECK(std::string(info.time_unit) == "s");
  for (std::size_t i = 0; i < want.size(); ++i) {
    CHECK(got[i].time == want[i].time);
    for (int k = 0; k < 3; ++k) {
      CHECK(got[i].pose[k].position.y == want[i].pose[k].position.y);
      CHECK(got[i].pose[k].orientation.w == want[i].pose[k].orientation.w);
      CHECK(got[i].valid[k] == want[i].valid[k]);
    }
    CHECK_FALSE(got[i].valid[3]);
    CHECK(got[i].pose[3].orientation.w == 1.0f);
  }
  // header errors name the column
  const std::string h = recordings::tracker_csv_header();
  CHECK(error_of(h.substr(0, h.find(",pelvis_px")) + ",pelvis_px\n").find("no column 'pelvis_py' (a pelvis tracker needs all 8") != std::string::npos);
  CHECK(error_of(h.substr(h.find(",") + 1) + "\n").find("no column 'time'") != std::string::npos);
  CHECK(error_of(h + ",head_px\n").find("column 'head_px' appears twice") != std::string::npos);
  CHECK(error_of(h + ",battery\n").find("unknown column 'battery'") != std::string::npos);
  // time units: 72 Hz in seconds, ms, us and ns (an XrTime-like origin), and a slow seconds stream
  struct Unit { const char* name; double factor, origin; };
  for (const Unit u : {Unit{"s", 1.0, 12.5}, Unit{"ms", 1e3, 0.0}, Unit{"us", 1e6, 5e6}, Unit{"ns", 1e9, 1.7e18}}) {
    CAPTURE(u.name);
    std::string s = h + "\n";
    for (int i = 0; i < 200; ++i) {
      std::ostringstream row;
      row << std::setprecision(17) << u.origin + u.factor * (i / 72.0);
      for (int c = 0; c < 32; ++c) row << (c % 8 == 6 || c % 8 == 7 ? ",1" : ",0");
      s += row.str() + "\n";
    }
    std::istringstream is(s);
    recordings::TrackerCsvInfo ti;
    const auto v = recordings::parse_tracker_csv(is, "t.csv", &ti);
    CHECK(std::string(ti.time_unit) == u.name);
    CHECK(ti.median_interval == doctest::Approx(1.0 / 72).epsilon(1e-3));
    const double t0 = u.factor == 1.0 ? u.origin : 0.0;  // seconds are kept as recorded
    CHECK(v[199].time - v[0].time == doctest::Approx(199 / 72.0).epsilon(1e-6));
    CHECK(v[0].time == doctest::Approx(t0));
  }
  {
    // a UTF-8 byte order mark (Excel, some .NET writers) and spaces around the fields
    std::string s = "\xEF\xBB\xBF" + h + "\n 0.5 ";
    for (int c = 0; c < 32; ++c) s += (c % 8 == 6 || c % 8 == 7) ? ", 1" : " , 0.25 ";
    std::istringstream is(s + "\n");
    const auto v = recordings::parse_tracker_csv(is, "bom.csv");
    REQUIRE(v.size() == 1);
    CHECK(v[0].time == 0.5);
    CHECK(v[0].pose[2].position.z == 0.25f);
    CHECK(v[0].valid[3]);
  }
  {
    std::string s = h + "\n";  // 1 Hz in seconds stays seconds
    for (int i = 0; i < 5; ++i) {
      s += std::to_string(i);
      for (int c = 0; c < 32; ++c) s += (c % 8 == 6 || c % 8 == 7) ? ",1" : ",0";
      s += "\n";
    }
    std::istringstream is(s);
    recordings::TrackerCsvInfo ti;
    const auto v = recordings::parse_tracker_csv(is, "slow.csv", &ti);
    CHECK(std::string(ti.time_unit) == "s");
    CHECK(v[4].time == 4.0);
  }
}
