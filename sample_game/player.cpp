#include "player.hpp"

#include <algorithm>
#include <cmath>

namespace walkthrough {

namespace {
constexpr float kSphereHeights[3] = {0.0f, 0.55f, 1.1f};  // sphere centres above feet + radius
constexpr float kMaxStep = 0.1f;                         // metres moved per collision substep
constexpr float kGroundNormalY = 0.65f;                  // steeper than ~50 degrees is a wall
}  // namespace

Player::Player(const CollisionWorld* world, const glm::vec3& eye, const glm::vec3& target, PlayerTuning tuning)
    : world_(world), tuning_(tuning) {
  glm::vec3 d = target - eye;
  if (glm::length(d) < 1e-6f) d = glm::vec3(0.0f, 0.0f, -1.0f);
  d = glm::normalize(d);
  yaw_ = std::atan2(d.x, -d.z);
  pitch_ = std::asin(std::clamp(d.y, -1.0f, 1.0f));
  feet_ = eye - glm::vec3(0.0f, tuning_.eye_height, 0.0f);
  const float down = world_ ? world_->ray_down(eye, 20.0f) : -1.0f;
  if (down >= 0.0f) {
    feet_ = eye - glm::vec3(0.0f, down - 0.01f, 0.0f);
    grounded_ = true;
  } else {
    flying_ = true;
  }
}

glm::vec3 Player::forward() const {
  return {std::cos(pitch_) * std::sin(yaw_), std::sin(pitch_), -std::cos(pitch_) * std::cos(yaw_)};
}

void Player::update(const InputFrame& in) {
  const uint32_t pressed = in.keys & ~previous_keys_;
  previous_keys_ = in.keys;
  if (pressed & kKeyFly) {
    flying_ = !flying_;
    velocity_ = glm::vec3(0.0f);
  }
  yaw_ += in.mouse_dx * tuning_.mouse_sensitivity;
  yaw_ = std::remainder(yaw_, 2.0f * 3.14159265f);
  pitch_ = std::clamp(pitch_ - in.mouse_dy * tuning_.mouse_sensitivity, -1.5f, 1.5f);

  const glm::vec3 flat_forward{std::sin(yaw_), 0.0f, -std::cos(yaw_)};
  const glm::vec3 right{std::cos(yaw_), 0.0f, std::sin(yaw_)};
  const float ahead = float(bool(in.keys & kKeyForward)) - float(bool(in.keys & kKeyBack));
  const float side = float(bool(in.keys & kKeyRight)) - float(bool(in.keys & kKeyLeft));
  const bool sprint = in.keys & kKeySprint;
  if (flying_) {
    glm::vec3 wish = forward() * ahead + right * side +
                     glm::vec3(0.0f, float(bool(in.keys & kKeyJump)) - float(bool(in.keys & kKeyDown)), 0.0f);
    if (glm::length(wish) > 1e-6f) wish = glm::normalize(wish);
    velocity_ = wish * (sprint ? tuning_.fly_speed * 2.0f : tuning_.fly_speed);
  } else {
    glm::vec3 wish = flat_forward * ahead + right * side;
    if (glm::length(wish) > 1e-6f) wish = glm::normalize(wish);
    wish *= sprint ? tuning_.sprint_speed : tuning_.walk_speed;
    // Full control on the ground, some in the air.
    const float control = grounded_ ? 1.0f : std::min(1.0f, 4.0f * in.dt);
    velocity_.x += (wish.x - velocity_.x) * control;
    velocity_.z += (wish.z - velocity_.z) * control;
    if (grounded_ && (pressed & kKeyJump)) velocity_.y = tuning_.jump_speed;
    velocity_.y = std::max(velocity_.y - tuning_.gravity * in.dt, -40.0f);
  }
  const float distance = glm::length(velocity_) * in.dt;
  const int steps = std::clamp(int(std::ceil(distance / kMaxStep)), 1, 64);
  grounded_ = false;
  for (int i = 0; i < steps; ++i) step(in.dt / float(steps));
}

void Player::step(float h) {
  feet_ += velocity_ * h;
  if (!world_) return;
  bool ground = false;
  for (int s = 0; s < 3; ++s) {
    const glm::vec3 offset(0.0f, tuning_.radius + kSphereHeights[s], 0.0f);
    glm::vec3 center = feet_ + offset;
    const glm::vec3 before = center;
    const auto contacts = world_->resolve_sphere(center, tuning_.radius);
    glm::vec3 push = center - before;
    for (const auto& c : contacts) {
      if (c.normal.y > kGroundNormalY && s == 0) ground = true;
      if (c.normal.y < -kGroundNormalY && velocity_.y > 0.0f) velocity_.y = 0.0f;  // head against a ceiling
      const float into = glm::dot(velocity_, c.normal);
      if (into < 0.0f && std::abs(c.normal.y) <= kGroundNormalY) velocity_ -= c.normal * into;  // slide along walls
    }
    if (s == 0 && ground && !flying_) {
      // Standing on a slope: lift straight up rather than sliding down it.
      push = glm::vec3(push.x, std::max(push.y, 0.0f), push.z);
      if (std::abs(push.x) + std::abs(push.z) < 0.5f * push.y) push.x = push.z = 0.0f;
    }
    feet_ += push;
  }
  if (ground) {
    grounded_ = true;
    if (velocity_.y < 0.0f) velocity_.y = 0.0f;
  }
}

}  // namespace walkthrough
