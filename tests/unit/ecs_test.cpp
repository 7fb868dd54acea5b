#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <string>

#include "engine/core/ecs.hpp"

namespace {

using engine::Entity;
using engine::Registry;

struct Position {
  float x = 0, y = 0;
};
struct Velocity {
  float dx = 0, dy = 0;
};
struct Tag {
  int id = 0;
};

TEST(Ecs, DestroyedIndexIsReusedWithNewGeneration) {
  Registry r;
  const Entity a = r.create();
  const Entity b = r.create();
  EXPECT_NE(a.index, b.index);
  EXPECT_EQ(r.entity_count(), 2u);
  r.destroy(a);
  EXPECT_FALSE(r.alive(a));
  EXPECT_EQ(r.entity_count(), 1u);
  const Entity c = r.create();
  EXPECT_EQ(c.index, a.index);
  EXPECT_EQ(c.generation, a.generation + 1);
  EXPECT_TRUE(r.alive(c));
  EXPECT_FALSE(r.alive(a));
  EXPECT_FALSE(a == c);
}

TEST(Ecs, StaleAndNullHandlesAreRejected) {
  Registry r;
  const Entity a = r.create();
  r.emplace<Tag>(a, Tag{7});
  r.destroy(a);
  const Entity reused = r.create();
  ASSERT_EQ(reused.index, a.index);
  EXPECT_FALSE(r.has<Tag>(a));
  EXPECT_FALSE(r.has<Tag>(reused));  // destroy removed the component with the old generation
  EXPECT_THROW(r.emplace<Tag>(a, Tag{1}), std::invalid_argument);
  EXPECT_THROW(r.get<Tag>(a), std::out_of_range);
  EXPECT_EQ(r.try_get<Tag>(a), nullptr);
  EXPECT_FALSE(r.alive(engine::kNullEntity));
  EXPECT_THROW(r.emplace<Tag>(engine::kNullEntity), std::invalid_argument);
  r.destroy(a);  // destroying a stale handle must not free the reused slot
  EXPECT_TRUE(r.alive(reused));
}

TEST(Ecs, EmplaceGetHasRemove) {
  Registry r;
  const Entity e = r.create();
  EXPECT_FALSE(r.has<Position>(e));
  r.emplace<Position>(e, Position{1.0f, 2.0f});
  ASSERT_TRUE(r.has<Position>(e));
  EXPECT_FLOAT_EQ(r.get<Position>(e).y, 2.0f);
  r.get<Position>(e).x = 5.0f;
  EXPECT_FLOAT_EQ(r.try_get<Position>(e)->x, 5.0f);
  // A second emplace replaces the value instead of adding a duplicate.
  r.emplace<Position>(e, Position{9.0f, 9.0f});
  EXPECT_EQ(r.count<Position>(), 1u);
  EXPECT_FLOAT_EQ(r.get<Position>(e).x, 9.0f);
  EXPECT_FALSE(r.has<Velocity>(e));
  r.remove<Position>(e);
  EXPECT_FALSE(r.has<Position>(e));
  EXPECT_EQ(r.count<Position>(), 0u);
  r.remove<Velocity>(e);  // removing an absent component is a no-op
  EXPECT_TRUE(r.alive(e));
}

TEST(Ecs, ViewAndEachVisitExactlyTheEntitiesWithAllComponents) {
  Registry r;
  std::vector<Entity> entities;
  for (int i = 0; i < 30; ++i) {
    const Entity e = r.create();
    entities.push_back(e);
    r.emplace<Position>(e, Position{float(i), 0.0f});
    if (i % 2 == 0) r.emplace<Velocity>(e, Velocity{1.0f, float(i)});
    if (i % 3 == 0) r.emplace<Tag>(e, Tag{i});
  }
  const auto two = r.view<Position, Velocity>();
  EXPECT_EQ(two.size(), 15u);
  const auto three = r.view<Position, Velocity, Tag>();
  ASSERT_EQ(three.size(), 5u);  // multiples of 6 below 30
  for (Entity e : three) EXPECT_EQ(r.get<Tag>(e).id % 6, 0);

  r.each<Position, Velocity>([](Entity, Position& p, Velocity& v) { p.y += v.dy; });
  for (int i = 0; i < 30; ++i) {
    EXPECT_FLOAT_EQ(r.get<Position>(entities[size_t(i)]).y, i % 2 == 0 ? float(i) : 0.0f);
  }
  int visited = 0;
  r.each<Tag, Position>([&](Entity e, Tag& t, Position& p) {
    ++visited;
    EXPECT_EQ(e, entities[size_t(t.id)]);
    EXPECT_FLOAT_EQ(p.x, float(t.id));
  });
  EXPECT_EQ(visited, 10);
  struct Unused {};
  EXPECT_TRUE((r.view<Position, Unused>().empty()));
}

TEST(Ecs, SwapAndPopKeepsComponentsWithTheirEntitiesUnderManyRemovals) {
  Registry r;
  std::vector<Entity> entities;
  for (int i = 0; i < 2000; ++i) {
    const Entity e = r.create();
    r.emplace<Tag>(e, Tag{i});
    r.emplace<Position>(e, Position{float(i) * 0.5f, 0.0f});
    entities.push_back(e);
  }
  std::mt19937 rng(1234);
  std::vector<size_t> order(entities.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::shuffle(order.begin(), order.end(), rng);
  std::vector<bool> removed(entities.size(), false);
  for (size_t k = 0; k < 1500; ++k) {
    const size_t i = order[k];
    if (k % 2 == 0) {
      r.remove<Tag>(entities[i]);
    } else {
      r.destroy(entities[i]);
    }
    removed[i] = true;
  }
  size_t tags = 0;
  for (size_t i = 0; i < entities.size(); ++i) {
    if (removed[i]) {
      EXPECT_FALSE(r.has<Tag>(entities[i]));
      continue;
    }
    ++tags;
    ASSERT_TRUE(r.has<Tag>(entities[i]));
    EXPECT_EQ(r.get<Tag>(entities[i]).id, int(i));
    EXPECT_FLOAT_EQ(r.get<Position>(entities[i]).x, float(i) * 0.5f);
  }
  EXPECT_EQ(r.count<Tag>(), tags);
  EXPECT_EQ(r.count<Tag>(), 500u);
  EXPECT_EQ(r.count<Position>(), 2000u - 750u);
  EXPECT_EQ((r.view<Tag, Position>().size()), 500u);
}

TEST(Ecs, SystemScheduleRunsSystemsInInsertionOrder) {
  engine::SystemSchedule schedule;
  std::string trace;
  float total_dt = 0.0f;
  schedule.add("input", [&](Registry&, float) { trace += "i"; });
  schedule.add("physics", [&](Registry&, float dt) {
    trace += "p";
    total_dt += dt;
  });
  schedule.add("render", [&](Registry& reg, float) {
    trace += "r";
    reg.create();
  });
  Registry r;
  schedule.run(r, 0.25f);
  schedule.run(r, 0.5f);
  EXPECT_EQ(trace, "ipripr");
  EXPECT_FLOAT_EQ(total_dt, 0.75f);
  EXPECT_EQ(r.entity_count(), 2u);
  EXPECT_EQ(schedule.names(), (std::vector<std::string>{"input", "physics", "render"}));
}

}  // namespace
