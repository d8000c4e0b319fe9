#include <gtest/gtest.h>

#include <stdexcept>

#include "osteon/loads.hpp"
#include "osteon/skeleton.hpp"

using namespace osteon;

namespace {
Skeleton tee() {
  Skeleton s;
  s.heads = {Vec3(0, 0, 0), Vec3(60, 0, 0), Vec3(30, 0, 0)};
  s.tails = {Vec3(60, 0, 0), Vec3(60, 40, 0), Vec3(30, -30, 0)};
  s.parents = {-1, 0, 0};
  return s;
}
}  // namespace

TEST(LoadTree, ChildrenAttachWhereTheirHeadProjects) {
  const LoadTree t = build_load_tree(tee(), -1, {});
  EXPECT_EQ(t.held_bone, 0);
  ASSERT_EQ(t.children[0].size(), 2u);
  for (const auto& [child, param] : t.children[0])
    EXPECT_NEAR(param, child == 1 ? 60.0 : 30.0, 1e-12);
  EXPECT_EQ(t.entry_param[1], 0.0);
}

TEST(LoadTree, HoldingAChildReversesThePath) {
  const LoadTree t = build_load_tree(tee(), 1, {});
  EXPECT_EQ(t.held_bone, 1);
  EXPECT_EQ(t.parent[0], 1);
  EXPECT_NEAR(t.entry_param[0], 60.0, 1e-12);  // the trunk is entered at its tail
  EXPECT_EQ(t.parent[2], 0);
}

TEST(LoadTree, ExtraRootsJoinTheNearestBone) {
  Skeleton s = tee();
  s.parents = {-1, -1, -1};
  const LoadTree t = build_load_tree(s, -1, {100, 10, 10});
  EXPECT_EQ(t.held_bone, 0);
  EXPECT_EQ(t.attached_roots.size(), 2u);
  EXPECT_EQ(t.parent[1], 0);
  EXPECT_EQ(t.parent[2], 0);
}

TEST(LoadTree, BadHeldBoneThrows) {
  EXPECT_THROW(build_load_tree(tee(), 7, {}), std::invalid_argument);
}

TEST(Skeleton, ValidationNamesTheProblem) {
  Skeleton s = tee();
  s.parents = {2, 0, 1};
  try {
    validate_skeleton(s);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("cycle"), std::string::npos);
  }
  s = tee();
  s.tails[1] = s.heads[1];
  EXPECT_THROW(validate_skeleton(s), std::invalid_argument);
}
