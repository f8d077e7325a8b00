#include "common/enum_names.h"

#include <gtest/gtest.h>

namespace cenote {
namespace {

enum class Scene { kCave, kReef, kWreck };

constexpr EnumName<Scene> kSceneNames[] = {{Scene::kCave, "cave"}, {Scene::kReef, "reef"}, {Scene::kWreck, "wreck"}};

// The message of what parseEnumName throws for `name`.
std::string parseError(const std::string& name, NameQuotes quotes) {
  try {
    parseEnumName(kSceneNames, name, "sim.scene = " + name, quotes);
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kInvalidArgument);
    return e.what();
  }
  return "nothing thrown for '" + name + "'";
}

TEST(EnumNames, NamesEveryValueAndFallsBackForOneOutsideTheTable) {
  EXPECT_STREQ(enumName(kSceneNames, Scene::kCave), "cave");
  EXPECT_STREQ(enumName(kSceneNames, Scene::kReef), "reef");
  EXPECT_STREQ(enumName(kSceneNames, Scene::kWreck), "wreck");
  EXPECT_STREQ(enumName(kSceneNames, static_cast<Scene>(7)), "?");
  EXPECT_STREQ(enumName(kSceneNames, static_cast<Scene>(7), "invalid"), "invalid");
}

TEST(EnumNames, ParsesEachNameBackToItsValue) {
  for (const EnumName<Scene>& n : kSceneNames) {
    EXPECT_EQ(parseEnumName(kSceneNames, n.name, "scene"), n.value) << n.name;
  }
}

TEST(EnumNames, UnknownNameIsAnErrorThatListsTheNamesAllowed) {
  EXPECT_EQ(parseError("lake", NameQuotes::kBare), "sim.scene = lake: must be cave, reef or wreck");
  EXPECT_EQ(parseError("lake", NameQuotes::kSingle), "sim.scene = lake: must be 'cave', 'reef' or 'wreck'");
  EXPECT_EQ(parseError("Cave", NameQuotes::kBare), "sim.scene = Cave: must be cave, reef or wreck");
  EXPECT_EQ(parseError("", NameQuotes::kBare), "sim.scene = : must be cave, reef or wreck");
}

TEST(EnumNames, ListsOneTwoAndManyNames) {
  constexpr EnumName<int> kOne[] = {{0, "a"}};
  constexpr EnumName<int> kTwo[] = {{0, "a"}, {1, "b"}};
  constexpr EnumName<int> kFour[] = {{0, "a"}, {1, "b"}, {2, "c"}, {3, "d"}};
  EXPECT_EQ(enumNameList(kOne), "a");
  EXPECT_EQ(enumNameList(kTwo, NameQuotes::kSingle), "'a' or 'b'");
  EXPECT_EQ(enumNameList(kFour), "a, b, c or d");
}

}  // namespace
}  // namespace cenote
