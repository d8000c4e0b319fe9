// The text parsers behind osteon.io's fast readers (cpp/src/readers_text.cpp).
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "osteon/readers.hpp"

using osteon::readers::parse_numbers;
using osteon::readers::parse_obj;

TEST(Readers, ObjVerticesAndFacesInFileOrder) {
  const auto d = parse_obj(
      "# a quad and a triangle\nv 0 0 0\nv 1 0 0\n  v 1 1 0 1.0\nv +0 1 0\nvt 0 0\nvn 0 0 1\n"
      "f 1/1/1 2/1/1 3/1/1 4/1/1\nf -4//1 -3//1 -1//1\r\n");
  ASSERT_EQ(d.error, "");
  EXPECT_FALSE(d.unsupported);
  EXPECT_EQ(d.vertices, (std::vector<double>{0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0}));
  EXPECT_EQ(d.counts, (std::vector<std::int32_t>{4, 3}));
  EXPECT_EQ(d.corners, (std::vector<std::int64_t>{0, 1, 2, 3, 0, 1, 3}));
}

TEST(Readers, ObjErrorsNameTheLine) {
  EXPECT_EQ(parse_obj("v 1 2\n").error, "line 1: a 'v' line has fewer than 3 numbers");
  EXPECT_EQ(parse_obj("v 1 2 3\nf 0 1 1\n").error, "line 2: face index 0 (OBJ indices start at 1)");
  EXPECT_EQ(parse_obj("v 1 2 3\nf 1 1\n").error, "line 2: an 'f' line has fewer than 3 corners");
  EXPECT_EQ(parse_obj("v 1 2 3\nf 1 1 99999999999999999999999\n").error,
            "line 2: a face index is too big for an integer");
  EXPECT_EQ(parse_obj("v 1 2 3\nf 1 1 -2\n").error,
            "line 2: a negative face index reaches before the first vertex");
  EXPECT_TRUE(parse_obj("v 1 2 \\\n 3\n").unsupported);
}

TEST(Readers, NumbersStopAtTheFirstWord) {
  std::vector<double> out;
  EXPECT_EQ(parse_numbers(" 1 2.5\n-3e4\t+7 ", out), std::string::npos);
  EXPECT_EQ(out, (std::vector<double>{1, 2.5, -3e4, 7}));
  out.clear();
  EXPECT_EQ(parse_numbers("1 2 x3 4", out), 4u);
  EXPECT_EQ(out.size(), 2u);
  out.clear();
  EXPECT_EQ(parse_numbers("1 2x", out), 2u);  // a number glued to a word is not a number
}
