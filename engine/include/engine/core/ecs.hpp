#pragma once
// Minimal entity-component system: an entity is an index plus a generation (so stale handles are
// detected), each component type lives in its own sparse set, and views iterate the smallest set.
#include <cassert>
#include <cstdint>
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <tuple>
#include <typeindex>
#include <unordered_map>
#include <vector>

namespace engine {

struct Entity {
  uint32_t index = UINT32_MAX;
  uint32_t generation = 0;
  bool valid() const { return index != UINT32_MAX; }
  bool operator==(const Entity&) const = default;
};
inline constexpr Entity kNullEntity{};

class SparseSetBase {
 public:
  virtual ~SparseSetBase() = default;
  virtual void remove(uint32_t index) = 0;
  virtual bool contains(uint32_t index) const = 0;
  virtual size_t size() const = 0;
  const std::vector<uint32_t>& entities() const { return dense_entities_; }

 protected:
  static constexpr uint32_t kAbsent = UINT32_MAX;
  std::vector<uint32_t> sparse_;          // entity index -> dense slot
  std::vector<uint32_t> dense_entities_;  // dense slot -> entity index
};

template <typename T>
class SparseSet final : public SparseSetBase {
 public:
  template <typename... Args>
  T& emplace(uint32_t index, Args&&... args) {
    if (index >= sparse_.size()) sparse_.resize(index + 1, kAbsent);
    if (sparse_[index] != kAbsent) {
      components_[sparse_[index]] = T{std::forward<Args>(args)...};
      return components_[sparse_[index]];
    }
    sparse_[index] = static_cast<uint32_t>(dense_entities_.size());
    dense_entities_.push_back(index);
    components_.push_back(T{std::forward<Args>(args)...});
    return components_.back();
  }
  void remove(uint32_t index) override {
    if (!contains(index)) return;
    // Swap-and-pop keeps the dense arrays packed.
    const uint32_t slot = sparse_[index];
    const uint32_t last_entity = dense_entities_.back();
    std::swap(components_[slot], components_.back());
    dense_entities_[slot] = last_entity;
    sparse_[last_entity] = slot;
    components_.pop_back();
    dense_entities_.pop_back();
    sparse_[index] = kAbsent;
  }
  bool contains(uint32_t index) const override {
    return index < sparse_.size() && sparse_[index] != kAbsent;
  }
  size_t size() const override { return components_.size(); }
  T& get(uint32_t index) { return components_[sparse_[index]]; }
  const T& get(uint32_t index) const { return components_[sparse_[index]]; }

 private:
  std::vector<T> components_;
};

class Registry {
 public:
  Entity create() {
    if (!free_list_.empty()) {
      const uint32_t index = free_list_.back();
      free_list_.pop_back();
      alive_[index] = true;
      return Entity{index, generations_[index]};
    }
    generations_.push_back(0);
    alive_.push_back(true);
    return Entity{static_cast<uint32_t>(generations_.size() - 1), 0};
  }

  void destroy(Entity e) {
    if (!alive(e)) return;
    for (auto& [type, set] : sets_) set->remove(e.index);
    alive_[e.index] = false;
    ++generations_[e.index];
    free_list_.push_back(e.index);
  }

  bool alive(Entity e) const {
    return e.index < generations_.size() && alive_[e.index] && generations_[e.index] == e.generation;
  }

  size_t entity_count() const { return generations_.size() - free_list_.size(); }

  template <typename T, typename... Args>
  T& emplace(Entity e, Args&&... args) {
    check_alive(e);
    return set<T>().emplace(e.index, std::forward<Args>(args)...);
  }
  template <typename T>
  void remove(Entity e) {
    check_alive(e);
    if (auto* s = find_set<T>()) s->remove(e.index);
  }
  template <typename T>
  bool has(Entity e) const {
    const auto* s = find_set<T>();
    return alive(e) && s && s->contains(e.index);
  }
  template <typename T>
  T& get(Entity e) {
    if (!has<T>(e)) throw std::out_of_range(std::string("entity lacks component ") + typeid(T).name());
    return set<T>().get(e.index);
  }
  template <typename T>
  const T& get(Entity e) const {
    if (!has<T>(e)) throw std::out_of_range(std::string("entity lacks component ") + typeid(T).name());
    return find_set<T>()->get(e.index);
  }
  template <typename T>
  T* try_get(Entity e) {
    return has<T>(e) ? &set<T>().get(e.index) : nullptr;
  }
  template <typename T>
  const T* try_get(Entity e) const {
    return has<T>(e) ? &find_set<T>()->get(e.index) : nullptr;
  }

  Entity handle(uint32_t index) const { return Entity{index, generations_[index]}; }

  // Calls fn(Entity, A&, B&, ...) for every entity that has all the listed components. Iterates the
  // smallest set and probes the others. Components must not be added or removed inside fn.
  template <typename... Ts, typename Fn>
  void each(Fn&& fn) {
    static_assert(sizeof...(Ts) > 0);
    SparseSetBase* sets[] = {find_set<Ts>()...};
    SparseSetBase* smallest = nullptr;
    for (auto* s : sets) {
      if (!s) return;
      if (!smallest || s->size() < smallest->size()) smallest = s;
    }
    const std::vector<uint32_t> candidates = smallest->entities();  // copy: fn may modify values
    for (uint32_t index : candidates) {
      if ((find_set<Ts>()->contains(index) && ...)) fn(handle(index), find_set<Ts>()->get(index)...);
    }
  }

  // The entities that currently have all the listed components, in the order of the smallest set.
  template <typename... Ts>
  std::vector<Entity> view() {
    std::vector<Entity> out;
    each<Ts...>([&](Entity e, Ts&...) { out.push_back(e); });
    return out;
  }

  template <typename T>
  size_t count() const {
    const auto* s = find_set<T>();
    return s ? s->size() : 0;
  }

 private:
  void check_alive(Entity e) const {
    if (!alive(e)) throw std::invalid_argument("stale or null entity handle");
  }
  template <typename T>
  SparseSet<T>& set() {
    auto& slot = sets_[std::type_index(typeid(T))];
    if (!slot) slot = std::make_unique<SparseSet<T>>();
    return static_cast<SparseSet<T>&>(*slot);
  }
  template <typename T>
  SparseSet<T>* find_set() {
    auto it = sets_.find(std::type_index(typeid(T)));
    return it == sets_.end() ? nullptr : static_cast<SparseSet<T>*>(it->second.get());
  }
  template <typename T>
  const SparseSet<T>* find_set() const {
    auto it = sets_.find(std::type_index(typeid(T)));
    return it == sets_.end() ? nullptr : static_cast<const SparseSet<T>*>(it->second.get());
  }

  std::vector<uint32_t> generations_;
  std::vector<bool> alive_;
  std::vector<uint32_t> free_list_;
  std::unordered_map<std::type_index, std::unique_ptr<SparseSetBase>> sets_;
};

// Systems run in the order they were added, once per frame.
class SystemSchedule {
 public:
  using System = std::function<void(Registry&, float dt)>;
  void add(std::string name, System system) { systems_.push_back({std::move(name), std::move(system)}); }
  void run(Registry& registry, float dt) {
    for (auto& s : systems_) s.fn(registry, dt);
  }
  std::vector<std::string> names() const {
    std::vector<std::string> out;
    for (auto& s : systems_) out.push_back(s.name);
    return out;
  }

 private:
  struct Entry {
    std::string name;
    System fn;
  };
  std::vector<Entry> systems_;
};

}  // namespace engine
