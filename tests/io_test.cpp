// Measurement files, model files, material cards and atomic output: every bad input gets one
// clear error naming file, line and column.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "scpkit/error.hpp"
#include "scpkit/io/atomic_file.hpp"
#include "scpkit/io/measurement.hpp"
#include "scpkit/io/model_file.hpp"
#include "scpkit/mechanics/material.hpp"
#include "test_support.hpp"

namespace scpkit {
namespace {

namespace fs = std::filesystem;

fs::path temp_dir() {
  fs::path d = fs::temp_directory_path() / ("scpkit_io_test_" + std::to_string(::getpid()));
  fs::create_directories(d);
  return d;
}

TEST(Measurement, ReadsMetadataUnitsAndComments) {
  const Measurement m = Measurement::parse(
      "\xEF\xBB\xBF# specimen: thread\n# plies: 2\n# length_mm: 100\n# free comment\n"
      "load_g, disp_mm ,note\r\n20,0.5,first\n# a comment between rows\n\n250,3.0,second\n",
      "t.csv");
  EXPECT_EQ(m.rows(), 2u);
  EXPECT_EQ(*m.meta("specimen"), "thread");
  EXPECT_EQ(*m.meta_positive_int("plies"), 2);
  const MeasurementColumn* load = m.find(Quantity::kLoad);
  ASSERT_NE(load, nullptr);
  EXPECT_NEAR(load->values[1], 250 * 9.80665e-3, 1e-12);
  EXPECT_EQ(m.line_of_row(1), 9);
  EXPECT_EQ(m.cell(0, 2), "first");
  const Signal r = select_response(m);
  EXPECT_EQ(r.name, "strain");
  EXPECT_NEAR(r.values[1], 0.03, 1e-15);
  EXPECT_EQ(select_input(m).name, "load_N");
}

TEST(Measurement, DisplacementWithoutLengthStaysInMillimetres) {
  const Measurement m = Measurement::parse("voltage_V,disp_mm\n0,0\n1,2\n", "s.csv");
  EXPECT_EQ(select_response(m).name, "disp_mm");
  EXPECT_EQ(select_input(m).name, "voltage_V");
}

TEST(Measurement, ReadsQuotedFieldsAsRfc4180) {
  // A CSV writer told to quote: the names and numbers inside the quotes, a comma and an
  // escaped quote inside a text column, spaces around a quoted field.
  const Measurement m = Measurement::parse(
      "\"load_g\",\"strain_pct\", \"note\" \n\"20\",0.5,\"a, \"\"b\"\"\"\n"
      "250, \"3.0\" ,\"\"\n",
      "q.csv");
  ASSERT_EQ(m.rows(), 2u);
  const MeasurementColumn* load = m.find(Quantity::kLoad);
  ASSERT_NE(load, nullptr);
  EXPECT_NEAR(load->values[0], 20 * 9.80665e-3, 1e-15);
  EXPECT_NEAR(select_response(m).values[1], 0.03, 1e-15);
  EXPECT_EQ(m.cell(0, 2), "a, \"b\"");
  EXPECT_EQ(m.cell(1, 2), "");
  // The same numbers unquoted read the same.
  const Measurement plain =
      Measurement::parse("load_g,strain_pct,note\n20,0.5,x\n250,3.0,y\n", "p.csv");
  EXPECT_EQ(select_response(plain).values, select_response(m).values);
  // csv_field writes what the reader reads back.
  for (const std::string text : {"plain", "a, b", "say \"x\"", " edge", "", "\"", ",,"}) {
    const Measurement back =
        Measurement::parse("load_g,strain,note\n1,2," + csv_field(text) + "\n", "w.csv");
    EXPECT_EQ(back.cell(0, 2), text) << csv_field(text);
  }
  EXPECT_THROW_MSG(Measurement::parse("load_g,strain_pct\n1,\"2\n", "q.csv"), InputError,
                   "q.csv:2:3: a quoted field has no closing quote on its line");
  EXPECT_THROW_MSG(Measurement::parse("load_g,strain_pct\n1,\"2\"x\n", "q.csv"), InputError,
                   "q.csv:2:6: text after the closing quote");
  EXPECT_THROW_MSG(Measurement::parse("load_g,strain_pct\n1,\"\"\n", "q.csv"), InputError,
                   "q.csv:2:3: empty value");
}

// SPEC.md ignores unknown columns: a name that starts like a known quantity is an unknown unit
// only where it reads as one unit and the file gives that quantity no other way.
TEST(Measurement, OtherColumnsWithAQuantitysPrefixAreIgnored) {
  const Measurement m = Measurement::parse(
      "time_s,time_stamp,load_g,load_cell_raw,temp_ambient_C,disp_mm,strain_gauge\n"
      "1,12:00:01,20,x,21.5,0.5,\n2,12:00:02,40,y,21.6,0.7,\n",
      "e.csv");
  EXPECT_EQ(m.rows(), 2U);
  ASSERT_NE(m.find(Quantity::kLoad), nullptr);
  EXPECT_DOUBLE_EQ(m.find(Quantity::kLoad)->values[1], 40 * 9.80665e-3);
  EXPECT_EQ(m.find(Quantity::kTemperature), nullptr);
  EXPECT_EQ(m.find(Quantity::kStrain), nullptr);
  ASSERT_NE(m.find(Quantity::kDisplacement), nullptr);
  EXPECT_DOUBLE_EQ(m.find(Quantity::kDisplacement)->values[1], 0.7);
}

// Unnamed columns are unknown ones too: a row index written by pandas, a trailing comma.
TEST(Measurement, UnnamedColumnsAreIgnored) {
  const Measurement unnamed = Measurement::parse(",load_g,strain_pct,\n0,1,2,\n1,3,4,\n", "e.csv");
  ASSERT_NE(unnamed.find(Quantity::kStrain), nullptr);
  EXPECT_DOUBLE_EQ(unnamed.find(Quantity::kStrain)->values[1], 0.04);
}

// A test of one specimen may name its response as a paired test does.
TEST(Measurement, APairedColumnAloneIsTheResponse) {
  const Signal scp = select_response(Measurement::parse("load_g,scp_strain_pct\n1,2\n", "e.csv"));
  EXPECT_EQ(scp.column, "scp_strain_pct");
  EXPECT_DOUBLE_EQ(scp.values[0], 0.02);
}

TEST(Measurement, EveryBadInputNamesFileLineAndColumn) {
  EXPECT_THROW_MSG(Measurement::parse("", "e.csv"), InputError, "e.csv:1: empty file");
  EXPECT_THROW_MSG(Measurement::parse("# only: metadata\n", "e.csv"), InputError, "no header");
  EXPECT_THROW_MSG(Measurement::parse("load_g,strain_pct\n", "e.csv"), InputError,
                   "e.csv:1: no data rows");
  EXPECT_THROW_MSG(Measurement::parse("load_g,strain_pct\n1,2\n3,abc\n", "e.csv"), InputError,
                   "e.csv:3:3: 'abc' is not a number (column 'strain_pct')");
  EXPECT_THROW_MSG(Measurement::parse("load_g,strain_pct\n1,nan\n", "e.csv"), InputError,
                   "e.csv:2:3: 'nan' is not a finite number");
  EXPECT_THROW_MSG(Measurement::parse("load_g,strain_pct\n1,inf\n", "e.csv"), InputError,
                   "not a finite");
  EXPECT_THROW_MSG(Measurement::parse("load_g,strain_pct\n1\n", "e.csv"), InputError,
                   "e.csv:2:2: 1 fields, the header has 2");
  EXPECT_THROW_MSG(Measurement::parse("load_g,strain_pct\n1,2,3\n", "e.csv"), InputError,
                   "e.csv:2:5: 3 fields");
  EXPECT_THROW_MSG(Measurement::parse("load_g,strain_pct\n1,\n", "e.csv"), InputError,
                   "e.csv:2:3: empty value");
  EXPECT_THROW_MSG(Measurement::parse("load_lb,strain_pct\n1,2\n", "e.csv"), InputError,
                   "e.csv:1:1: unknown unit 'lb' in column 'load_lb'");
  EXPECT_THROW_MSG(Measurement::parse("load_g,disp_in\n1,2\n", "e.csv"), InputError,
                   "e.csv:1:8: unknown unit 'in' in column 'disp_in'");
  EXPECT_THROW_MSG(Measurement::parse("load_g,load_N,strain\n1,2,3\n", "e.csv"), InputError,
                   "e.csv:1:8: a second load column");
  EXPECT_THROW_MSG(Measurement::parse("load_g,load_g\n1,2\n", "e.csv"), InputError,
                   "appears twice");
  EXPECT_THROW_MSG(Measurement::parse("voltage_V,segment\n1,0.5\n", "e.csv"), InputError,
                   "not an integer");
  const Measurement m = Measurement::parse("# plies: two\nload_g,strain\n1,2\n", "e.csv");
  EXPECT_THROW_MSG(m.meta_positive_int("plies"), InputError,
                   "e.csv:1: metadata 'plies' must be a number");
  EXPECT_THROW_MSG(select_response(Measurement::parse("load_g,time_s\n1,2\n", "e.csv")), InputError,
                   "no response column");
  EXPECT_THROW_MSG(
      select_input(Measurement::parse("load_g,voltage_V,strain\n1,2,3\n2,3,4\n", "e.csv")),
      InputError, "several inputs vary");
  EXPECT_THROW_MSG(select_input(Measurement::parse("load_g,strain\n1,2\n1,3\n", "e.csv")),
                   InputError, "no varying input");
  EXPECT_THROW_MSG(Measurement::read("/nonexistent/x.csv"), InputError,
                   "/nonexistent/x.csv: cannot open");
}

TEST(AtomicFile, WritesWholeFilesAndLeavesNoTemporaries) {
  const fs::path d = temp_dir();
  const fs::path f = d / "out.txt";
  write_file_atomically(f, "first\n");
  write_file_atomically(f, "second\n");
  EXPECT_EQ(read_text_file(f), "second\n");
  EXPECT_THROW_MSG(write_file_atomically(d / "missing" / "x.txt", "y"), InputError,
                   "missing/x.txt");
  int files = 0;
  for (const auto& e : fs::directory_iterator(d)) files += e.is_regular_file() ? 1 : 0;
  EXPECT_EQ(files, 1);  // no .tmp left behind
  fs::remove_all(d);
}

TEST(ModelFile, RoundTripsExactlyAndLocatesJsonErrors) {
  std::mt19937 rng(51);
  ModelFile mf;
  mf.input = "load_N";
  mf.response = "strain";
  mf.response_column = "thread_strain_pct";
  mf.op = HysteresisOperator(testing::random_model(rng, PreisachGrid{0.196, 2.45, 7}));
  mf.specimen.plies = 2;
  mf.specimen.material = "nylon-110-34-dtex";
  CoilGeometry c;
  c.wire_d_m = 0.25e-3;
  c.mean_D_m = 0.35e-3;
  c.coils = 440;
  c.legs = 2;
  mf.specimen.coil = c;
  mf.scp_gain = GainFit{6.9447, 0.0173, 0.999, 300};
  const fs::path d = temp_dir();
  save_model(d / "m.json", mf);
  const ModelFile back = load_model(d / "m.json");
  ASSERT_NE(back.preisach(), nullptr);
  EXPECT_EQ(back.preisach()->weights(),
            mf.preisach()->weights());  // exact: shortest round-trip doubles
  EXPECT_EQ(back.preisach()->bias(), mf.preisach()->bias());
  EXPECT_EQ(back.preisach()->grid().lo, 0.196);
  EXPECT_EQ(back.response_column, "thread_strain_pct");
  EXPECT_EQ(back.scp_gain->gain, 6.9447);
  EXPECT_EQ(back.specimen.coil->legs, 2);
  // Every family round-trips exactly.
  GpiModel g;
  g.right = {1.1, 0.048};
  g.left = {1.236, 0.088};
  g.radii = {0.0, 0.1, 0.2};
  g.weights = {-0.1, -0.2, -0.05};
  g.bias = 0.396;
  g.v_min = 0.0;
  g.v_max = 5.1;
  for (const HysteresisOperator& op :
       {HysteresisOperator(g), HysteresisOperator(PolynomialModel{{0.008, -0.173}, 0.0, 5.1}),
        HysteresisOperator(PolynomialModel{{1.0, 2.0, -0.1}, 0.5, 4.0}),
        HysteresisOperator(LonelyModel{testing::random_model(rng, PreisachGrid{0.0, 5.0, 4}),
                                       {-0.1, -0.2, 0.0, -0.05}},
                           0.5, 4.5)}) {
    mf.op = op;
    save_model(d / "m.json", mf);
    const ModelFile b2 = load_model(d / "m.json");
    EXPECT_EQ(b2.op.family(), op.family());
    const std::vector<double> u = {0.5, 3.0, 1.0, 4.0, 2.0};
    EXPECT_EQ(b2.op.simulate(u), op.simulate(u));
    EXPECT_EQ(b2.op.input_min(), op.input_min());
  }
  std::ofstream(d / "bad.json") << "{\n  \"format\": \"scpkit-model\",\n  oops\n}\n";
  EXPECT_THROW_MSG(load_model(d / "bad.json"), InputError, "bad.json:3:");
  std::ofstream(d / "other.json") << "{\"format\": \"something\"}";
  EXPECT_THROW_MSG(load_model(d / "other.json"), InputError, "not an scpkit model file");
  fs::remove_all(d);
}

TEST(Material, BadCardsGetLocatedErrors) {
  const fs::path d = temp_dir();
  const std::string good_head =
      "id = \"card\"\nname = \"x\"\n[ply]\nlinear_density_dtex = 110\ndensity_g_cm3 = 1.14\n"
      "diameter_mm = 0.111\n[tensile_modulus]\nvalue_GPa = 3.9\nsigma_GPa = 1\nsource = \"s\"\n"
      "[shear_modulus]\nvalue_GPa = 2\nsigma_GPa = 0.6\nsource = \"s\"\n";
  std::ofstream(d / "card.toml") << good_head;
  EXPECT_NO_THROW(load_material(d / "card.toml"));
  std::ofstream(d / "card.toml") << good_head
                                 << "[[geometry]]\nplies = 2\nd_mm = 0.25\nD_mm = 0.1\nn = 440\n";
  EXPECT_THROW_MSG(load_material(d / "card.toml"), InputError, "spring index");
  std::ofstream(d / "card.toml")
      << "id = \"card\"\nname = \"x\"\n[ply]\nlinear_density_dtex = -1\n";
  EXPECT_THROW_MSG(load_material(d / "card.toml"), InputError,
                   "card.toml:4:23: 'linear_density_dtex' must be > 0");
  std::ofstream(d / "card.toml") << good_head << "colour = \"red\"\n";
  EXPECT_THROW_MSG(load_material(d / "card.toml"), InputError, "unknown key 'colour'");
  std::ofstream(d / "card.toml") << "id = = 3\n";
  EXPECT_THROW_MSG(load_material(d / "card.toml"), InputError, "card.toml:1:");
  EXPECT_THROW_MSG(find_material("no-such-thread"), InputError,
                   "no material card 'no-such-thread.toml'");
  fs::remove_all(d);
}

}  // namespace
}  // namespace scpkit
