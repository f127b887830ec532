// Paths: checked against independent derivations (polar form, chord sums, finite differences, the
// textbook curvature of a logarithmic spiral), never against the formulas the implementation uses.
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "model/common/errors.hpp"
#include "model/compensation/path.hpp"

namespace jointcomp {
namespace {

using ::testing::HasSubstr;

// The spiral written in polar form, independently of Path: p(theta) = c + a e^(b theta) (cos, sin, 0).
Eigen::Vector3d polarSpiralPoint(const SpiralSpec& spec, double theta) {
  const double radius = spec.a * std::exp(spec.b * theta);
  return spec.centre + radius * Eigen::Vector3d(std::cos(theta), std::sin(theta), 0.0);
}

// Arc length of the polar spiral between two angles by a fine chord sum (converges as 1/n^2).
double chordLength(const SpiralSpec& spec, double theta_from, double theta_to, int chords) {
  double length = 0.0;
  Eigen::Vector3d previous = polarSpiralPoint(spec, theta_from);
  for (int i = 1; i <= chords; ++i) {
    const double theta = theta_from + (theta_to - theta_from) * i / chords;
    const Eigen::Vector3d next = polarSpiralPoint(spec, theta);
    length += (next - previous).norm();
    previous = next;
  }
  return length;
}

// Expects `call` to throw InvalidArgument whose message contains every one of `fragments`.
template <typename Call>
void expectInvalidArgument(Call call, const std::vector<std::string>& fragments) {
  try {
    call();
    ADD_FAILURE() << "no InvalidArgument thrown; expected a message with '" << fragments.front() << "'";
  } catch (const InvalidArgument& error) {
    for (const std::string& fragment : fragments) {
      EXPECT_THAT(error.what(), HasSubstr(fragment));
    }
  }
}

std::vector<SpiralSpec> spiralVariants() {
  SpiralSpec paper;
  paper.centre = Eigen::Vector3d(0.9, -0.1, 0.2);  // the paper's test plane z = 200 mm
  SpiralSpec inwards;
  inwards.a = 0.3;
  inwards.b = -0.2;
  inwards.theta_start = -1.0;
  inwards.theta_end = 5.0;
  inwards.centre = Eigen::Vector3d(-0.4, 0.5, 1.1);
  SpiralSpec nearly_circular;
  nearly_circular.a = 0.05;
  nearly_circular.b = 1e-4;
  nearly_circular.theta_start = 0.5;
  nearly_circular.theta_end = 2.0;
  return {SpiralSpec{}, paper, inwards, nearly_circular};
}

TEST(SpiralSpec, DefaultsAreThePapers) {
  const SpiralSpec spec;
  EXPECT_EQ(spec.a, 0.024);
  EXPECT_EQ(spec.b, 0.15);
  EXPECT_EQ(spec.theta_start, 0.0);
  EXPECT_DOUBLE_EQ(spec.theta_end, 4.0 * std::acos(-1.0));
  EXPECT_EQ(spec.centre, Eigen::Vector3d::Zero());
}

TEST(LogarithmicSpiral, LengthMatchesChordSumOfThePolarForm) {
  for (const SpiralSpec& spec : spiralVariants()) {
    const Path path = logarithmicSpiral(spec);
    const double reference = chordLength(spec, spec.theta_start, spec.theta_end, 200000);
    EXPECT_NEAR(path.length(), reference, 1e-9 * reference) << "b = " << spec.b;
  }
  // The paper's spiral, to the millimetre by hand: 0.024 sqrt(1.0225) / 0.15 (e^(0.6 pi) - 1).
  EXPECT_NEAR(logarithmicSpiral(SpiralSpec{}).length(), 0.9038, 1e-3);
}

TEST(LogarithmicSpiral, PointsLieOnTheSpiralInTheCentrePlane) {
  for (const SpiralSpec& spec : spiralVariants()) {
    const Path path = logarithmicSpiral(spec);
    for (int i = 0; i <= 400; ++i) {
      const double s = path.length() * i / 400.0;
      const Eigen::Vector3d offset = path.pointAt(s) - spec.centre;
      EXPECT_NEAR(offset.z(), 0.0, 1e-15);
      // The radius fixes theta through R = a e^(b theta); the direction must then be (cos, sin).
      const double radius = offset.head<2>().norm();
      const double theta = std::log(radius / spec.a) / spec.b;
      if (std::abs(spec.b) > 0.01) {  // for b -> 0 the radius no longer resolves theta
        EXPECT_NEAR(offset.x() / radius, std::cos(theta), 1e-9);
        EXPECT_NEAR(offset.y() / radius, std::sin(theta), 1e-9);
        EXPECT_GE(theta, spec.theta_start - 1e-9);
        EXPECT_LE(theta, spec.theta_end + 1e-9);
      }
    }
  }
}

TEST(LogarithmicSpiral, EndsAreTheEndsOfTheThetaRange) {
  for (const SpiralSpec& spec : spiralVariants()) {
    const Path path = logarithmicSpiral(spec);
    EXPECT_LT((path.pointAt(0.0) - polarSpiralPoint(spec, spec.theta_start)).norm(), 1e-14);
    EXPECT_LT((path.pointAt(path.length()) - polarSpiralPoint(spec, spec.theta_end)).norm(), 1e-12);
  }
}

TEST(LogarithmicSpiral, ArcLengthBetweenPointsIsTheirDifferenceInS) {
  // Chord sum of the polar form between the angles of pointAt(s1) and pointAt(s2) must be s2 - s1.
  SpiralSpec spec;
  spec.centre = Eigen::Vector3d(0.3, 0.2, 0.1);
  const Path path = logarithmicSpiral(spec);
  const auto angle_of = [&](double s) {
    const Eigen::Vector3d offset = path.pointAt(s) - spec.centre;
    return std::log(offset.head<2>().norm() / spec.a) / spec.b;
  };
  for (const auto& [s1, s2] :
       std::vector<std::pair<double, double>>{{0.0, 0.1}, {0.1, 0.45}, {0.3, 0.9}, {0.0, path.length()}}) {
    EXPECT_NEAR(chordLength(spec, angle_of(s1), angle_of(s2), 100000), s2 - s1, 1e-9) << s1 << " to " << s2;
  }
  // Consecutive samples a small step apart are that step apart (chord = arc to O(step^3)).
  const double step = 1e-4;
  for (double s = 0.0; s + step <= path.length(); s += 0.01) {
    EXPECT_NEAR((path.pointAt(s + step) - path.pointAt(s)).norm(), step, 1e-10);
  }
}

TEST(LogarithmicSpiral, TangentIsTheFiniteDifferenceOfPointAt) {
  for (const SpiralSpec& spec : spiralVariants()) {
    const Path path = logarithmicSpiral(spec);
    const double h = 1e-6;
    for (int i = 1; i < 100; ++i) {
      const double s = path.length() * i / 100.0;
      const Eigen::Vector3d difference = (path.pointAt(s + h) - path.pointAt(s - h)) / (2.0 * h);
      const Eigen::Vector3d tangent = path.tangentAt(s);
      EXPECT_NEAR(tangent.norm(), 1.0, 1e-14);
      EXPECT_LT((tangent - difference).norm(), 1e-7) << "s = " << s;
    }
  }
}

TEST(LogarithmicSpiral, CurvatureVectorIsTheDerivativeOfTheTangent) {
  for (const SpiralSpec& spec : spiralVariants()) {
    const Path path = logarithmicSpiral(spec);
    const double h = 1e-5;
    for (int i = 1; i < 50; ++i) {
      const double s = path.length() * i / 50.0;
      const Eigen::Vector3d difference = (path.tangentAt(s + h) - path.tangentAt(s - h)) / (2.0 * h);
      const Eigen::Vector3d curvature = path.curvatureVectorAt(s);
      EXPECT_LT((curvature - difference).norm(), 1e-6 * curvature.norm() + 1e-9) << "s = " << s;
      EXPECT_NEAR(curvature.dot(path.tangentAt(s)), 0.0, 1e-12);
      // Textbook curvature of a logarithmic spiral: 1 / (R sqrt(1 + b^2)).
      const double radius = (path.pointAt(s) - spec.centre).norm();
      EXPECT_NEAR(curvature.norm(), 1.0 / (radius * std::sqrt(1.0 + spec.b * spec.b)), 1e-12 * curvature.norm());
      // It points to the inside of the turn: towards the centre.
      EXPECT_LT(curvature.dot(path.pointAt(s) - spec.centre), 0.0);
    }
  }
}

TEST(LogarithmicSpiral, RejectsBadSpecNamingTheField) {
  const double nan = std::nan("");
  const double inf = std::numeric_limits<double>::infinity();
  const auto with = [](auto change) {
    SpiralSpec spec;
    change(spec);
    return [spec] { logarithmicSpiral(spec); };
  };
  expectInvalidArgument(with([](SpiralSpec& s) { s.a = 0.0; }), {"SpiralSpec.a"});
  expectInvalidArgument(with([](SpiralSpec& s) { s.a = -0.01; }), {"SpiralSpec.a"});
  expectInvalidArgument(with([&](SpiralSpec& s) { s.a = nan; }), {"SpiralSpec.a", "finite"});
  expectInvalidArgument(with([](SpiralSpec& s) { s.b = 0.0; }), {"SpiralSpec.b"});
  expectInvalidArgument(with([&](SpiralSpec& s) { s.b = inf; }), {"SpiralSpec.b", "finite"});
  expectInvalidArgument(with([&](SpiralSpec& s) { s.theta_start = nan; }), {"SpiralSpec.theta_start"});
  expectInvalidArgument(with([&](SpiralSpec& s) { s.theta_end = -inf; }), {"SpiralSpec.theta_end"});
  expectInvalidArgument(with([](SpiralSpec& s) { s.theta_end = s.theta_start; }),
                        {"SpiralSpec.theta_end", "SpiralSpec.theta_start"});
  expectInvalidArgument(with([](SpiralSpec& s) { s.theta_end = -1.0; }), {"SpiralSpec.theta_end"});
  expectInvalidArgument(with([&](SpiralSpec& s) { s.centre.y() = nan; }), {"SpiralSpec.centre.y"});
  expectInvalidArgument(with([](SpiralSpec& s) { s.theta_end = 1e4; }), {"SpiralSpec", "arc length"});
}

TEST(Path, RejectsArcLengthOutsideTheRangeAndClampsRounding) {
  const Path path = logarithmicSpiral(SpiralSpec{});
  expectInvalidArgument([&] { path.pointAt(-1e-3); }, {"pointAt", "s"});
  expectInvalidArgument([&] { path.pointAt(path.length() + 1e-3); }, {"pointAt"});
  expectInvalidArgument([&] { path.tangentAt(std::nan("")); }, {"tangentAt"});
  expectInvalidArgument([&] { path.curvatureVectorAt(2.0); }, {"curvatureVectorAt"});
  // A rounding error past the end is the end.
  EXPECT_EQ(path.pointAt(path.length() * (1.0 + 1e-14)), path.pointAt(path.length()));
  EXPECT_EQ(path.pointAt(-1e-18), path.pointAt(0.0));
}

TEST(StraightLine, IsTheSegmentWalkedAtUnitSpeed) {
  const Eigen::Vector3d start(0.8, -0.2, 0.3);
  const Eigen::Vector3d end(0.5, 0.2, 0.3);
  const Path path = straightLine(start, end);
  EXPECT_DOUBLE_EQ(path.length(), 0.5);  // a 3-4-5 triangle scaled by 0.1
  const Eigen::Vector3d direction(-0.6, 0.8, 0.0);
  for (int i = 0; i <= 10; ++i) {
    const double s = 0.05 * i;
    EXPECT_LT((path.pointAt(s) - (start + s * direction)).norm(), 1e-15);
    EXPECT_LT((path.tangentAt(s) - direction).norm(), 1e-15);
    EXPECT_EQ(path.curvatureVectorAt(s), Eigen::Vector3d::Zero());
  }
  EXPECT_EQ(path.pointAt(path.length()), end);
}

TEST(StraightLine, RejectsBadEnds) {
  const Eigen::Vector3d point(1.0, 2.0, 3.0);
  expectInvalidArgument([&] { straightLine(point, point); }, {"straightLine", "zero-length"});
  expectInvalidArgument([&] { straightLine(Eigen::Vector3d(std::nan(""), 0, 0), point); }, {"straightLine", "start"});
  expectInvalidArgument([&] { straightLine(point, Eigen::Vector3d(0, std::numeric_limits<double>::infinity(), 0)); },
                        {"straightLine", "end"});
}

TEST(Polyline, InterpolatesLinearlyByArcLength) {
  // An L: 0.3 m along x, then 0.4 m along z, with a duplicated corner that must not matter.
  const Path path = polyline(
      {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(0.3, 0, 0), Eigen::Vector3d(0.3, 0, 0), Eigen::Vector3d(0.3, 0, 0.4)});
  EXPECT_DOUBLE_EQ(path.length(), 0.7);
  EXPECT_LT((path.pointAt(0.15) - Eigen::Vector3d(0.15, 0, 0)).norm(), 1e-15);
  EXPECT_LT((path.pointAt(0.3) - Eigen::Vector3d(0.3, 0, 0)).norm(), 1e-15);
  EXPECT_LT((path.pointAt(0.5) - Eigen::Vector3d(0.3, 0, 0.2)).norm(), 1e-15);
  EXPECT_LT((path.tangentAt(0.1) - Eigen::Vector3d::UnitX()).norm(), 1e-15);
  EXPECT_LT((path.tangentAt(0.3) - Eigen::Vector3d::UnitZ()).norm(), 1e-15);  // the segment ahead
  EXPECT_LT((path.tangentAt(0.7) - Eigen::Vector3d::UnitZ()).norm(), 1e-15);
  // A repeated last point must not leave a zero-length segment at the end.
  const Path repeated_end =
      polyline({Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(0, 0.2, 0), Eigen::Vector3d(0, 0.2, 0)});
  EXPECT_EQ(repeated_end.pointAt(repeated_end.length()), Eigen::Vector3d(0, 0.2, 0));
  EXPECT_EQ(repeated_end.tangentAt(repeated_end.length()), Eigen::Vector3d::UnitY());
  // Tangent is the finite difference of pointAt away from the corner.
  for (const double s : {0.05, 0.2, 0.35, 0.6}) {
    const double h = 1e-7;
    const Eigen::Vector3d difference = (path.pointAt(s + h) - path.pointAt(s - h)) / (2.0 * h);
    EXPECT_LT((path.tangentAt(s) - difference).norm(), 1e-8);
  }
}

TEST(Polyline, RejectsDegenerateInput) {
  expectInvalidArgument([] { polyline({}); }, {"polyline", "at least 2"});
  expectInvalidArgument(
      [] {
        polyline({Eigen::Vector3d(1, 1, 1), Eigen::Vector3d(1, 1, 1)});
      },
      {"polyline", "at least 2"});
  expectInvalidArgument(
      [] {
        polyline({Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(std::nan(""), 0, 0)});
      },
      {"points[2]"});
}

// ---- CSV ----------------------------------------------------------------------------------------

class PolylineCsv : public ::testing::Test {
protected:
  void SetUp() override {
    std::string pattern = (std::filesystem::temp_directory_path() / "jointcomp_test_path_XXXXXX").string();
    ASSERT_NE(mkdtemp(pattern.data()), nullptr);
    directory_ = pattern;
  }
  void TearDown() override { std::filesystem::remove_all(directory_); }

  std::string write(const std::string& name, const std::string& contents) const {
    const std::string file = (directory_ / name).string();
    std::ofstream(file) << contents;
    return file;
  }

  std::filesystem::path directory_;
};

TEST_F(PolylineCsv, ReadsMillimetresIntoMetresWithColumnsInAnyOrder) {
  const std::string file = write("good.csv",
                                 "# a measured path\n"
                                 "#   units: mm\n"
                                 "\n"
                                 "index, Z ,note,y,X\r\n"
                                 "0, 200, start, 0, 1000\r\n"
                                 "1, 200, , 300, 1000\r\n"
                                 "\n"
                                 "2,+200.0,corner,300,1.4e3\r\n");
  const Path path = polylineFromCsv(file);
  EXPECT_NEAR(path.length(), 0.7, 1e-15);
  EXPECT_LT((path.pointAt(0.0) - Eigen::Vector3d(1.0, 0.0, 0.2)).norm(), 1e-15);
  EXPECT_LT((path.pointAt(0.3) - Eigen::Vector3d(1.0, 0.3, 0.2)).norm(), 1e-15);
  EXPECT_LT((path.pointAt(0.7) - Eigen::Vector3d(1.4, 0.3, 0.2)).norm(), 1e-15);
}

TEST_F(PolylineCsv, RoundTripsASampledSpiral) {
  SpiralSpec spec;
  spec.centre = Eigen::Vector3d(0.9, 0.0, 0.2);
  const Path spiral = logarithmicSpiral(spec);
  std::ofstream out(directory_ / "spiral.csv");
  out.precision(17);
  out << "x,y,z\n";
  const int count = 2000;
  std::vector<Eigen::Vector3d> points;
  for (int i = 0; i <= count; ++i) {
    const Eigen::Vector3d p = spiral.pointAt(spiral.length() * i / count);
    points.push_back(p);
    out << p.x() * 1e3 << "," << p.y() * 1e3 << "," << p.z() * 1e3 << "\n";
  }
  out.close();
  const Path read = polylineFromCsv((directory_ / "spiral.csv").string());
  const Path direct = polyline(points);
  EXPECT_NEAR(read.length(), direct.length(), 1e-12);
  // A chord polyline is a little shorter than the arc it samples.
  EXPECT_LT(read.length(), spiral.length());
  EXPECT_NEAR(read.length(), spiral.length(), 1e-5 * spiral.length());
  for (int i = 0; i <= 10; ++i) {
    const double s = read.length() * i / 10.0;
    EXPECT_LT((read.pointAt(s) - direct.pointAt(s)).norm(), 1e-12);
  }
}

TEST_F(PolylineCsv, ErrorsNameFileLineAndColumn) {
  struct Case {
    std::string name;
    std::string contents;
    std::vector<std::string> fragments;  // besides the file path
  };
  const std::vector<Case> cases = {
      {"missing_column.csv", "# c\nx,y,elevation\n1,2,3\n4,5,6\n", {":2:", "column 'z'"}},
      {"duplicate_column.csv", "x,y,z,X\n1,2,3,4\n", {":1:", "column 4 ('x')", "column 1"}},
      {"non_numeric.csv", "x,y,z\n1,2,3\n4,five,6\n", {":3:", "column 2 ('y')", "non-numeric", "five"}},
      {"trailing_junk.csv", "x,y,z\n1,2,3\n4,5,6mm\n", {":3:", "column 3 ('z')", "non-numeric"}},
      {"empty_cell.csv", "note,z,y,x\na,1,2,3\nb,,5,6\n", {":3:", "column 2 ('z')", "non-numeric"}},
      {"not_finite.csv", "x,y,z\n1,2,3\ninf,5,6\n", {":3:", "column 1 ('x')", "non-finite"}},
      {"nan.csv", "y,z,x\n1,2,3\n4,5,nan\n", {":3:", "column 3 ('x')", "non-finite"}},
      {"overflow.csv", "x,y,z\n1,2,3\n4,5,1e999\n", {":3:", "column 3 ('z')", "non-finite"}},
      {"too_few_cells.csv", "x,y,z,note\n1,2,3,a\n4,5,6\n", {":3:", "column 4 ('note') is missing"}},
      {"too_many_cells.csv", "x,y,z\n1,2,3\n4,5,6,7\n", {":3:", "column 4 is not in the header"}},
      {"one_point.csv", "x,y,z\n1,2,3\n", {":2:", "only 1 data point", "x, y, z"}},
      {"no_points.csv", "# header only\nx,y,z\n", {":2:", "only 0 data point"}},
      {"no_header.csv", "# nothing\n\n", {":2:", "no header"}},
      {"zero_length.csv", "x,y,z\n1,2,3\n1,2,3\n1.0,2.0,3.0\n", {":2-4:", "zero length"}},
  };
  for (const Case& bad : cases) {
    const std::string file = write(bad.name, bad.contents);
    std::vector<std::string> fragments = bad.fragments;
    fragments.push_back(file);
    SCOPED_TRACE(bad.name);
    expectInvalidArgument([&] { polylineFromCsv(file); }, fragments);
  }
  const std::string missing = (directory_ / "does_not_exist.csv").string();
  expectInvalidArgument([&] { polylineFromCsv(missing); }, {missing, "cannot open"});
}

}  // namespace
}  // namespace jointcomp
