// An outside project using the installed Ridgeline::bullet: a sphere dropped on a flat terrain
// through Bullet comes to rest on it, and a Bullet ray test hits the ground where Ridgeline does.
#include <btBulletDynamicsCommon.h>
#include <ridgeline/bullet/terrain_shape.h>
#include <ridgeline/bullet/terrain_sync.h>
#include <ridgeline/terrain.h>

#include <cmath>
#include <cstdio>
#include <vector>

int main() {
  ridgeline::HeightfieldDesc desc;
  desc.width = desc.height = 33;
  const std::vector<float> values(33 * 33, 4.0f);
  auto terrain = ridgeline::Terrain::create(ridgeline::Heightfield::create(desc, values).value()).value();
  auto shape = ridgeline::bullet::TerrainShape::create(terrain, {.origin = {16, 0, 16}});
  if (!shape) {
    std::fprintf(stderr, "%s\n", shape.error().message.c_str());
    return 1;
  }
  btDefaultCollisionConfiguration config;
  btCollisionDispatcher dispatcher(&config);
  btDbvtBroadphase broadphase;
  btSequentialImpulseConstraintSolver solver;
  btDiscreteDynamicsWorld world(&dispatcher, &broadphase, &solver, &config);
  world.setGravity(btVector3(0, -9.81f, 0));
  btCollisionObject ground;
  ground.setCollisionShape(shape->get());
  world.addCollisionObject(&ground);
  auto sync = ridgeline::bullet::TerrainSync::create(&world, &ground);
  if (!sync) return 1;
  btSphereShape ball(0.5f);
  btVector3 inertia;
  ball.calculateLocalInertia(1, inertia);
  btDefaultMotionState state(btTransform(btQuaternion::getIdentity(), btVector3(0, 6, 0)));
  btRigidBody body(btRigidBody::btRigidBodyConstructionInfo(1, &state, &ball, inertia));
  world.addRigidBody(&body);
  for (int i = 0; i < 240; ++i) {
    (void)sync->update();
    world.stepSimulation(1.0f / 60.0f, 0);
  }
  const double rest = (*shape)->to_world(body.getWorldTransform().getOrigin()).y - 0.5;
  btCollisionWorld::ClosestRayResultCallback ray(btVector3(1, 10, 1), btVector3(1, -10, 1));
  world.rayTest(ray.m_rayFromWorld, ray.m_rayToWorld, ray);
  world.removeRigidBody(&body);
  world.removeCollisionObject(&ground);
  if (std::abs(rest - 4.0) > 1e-3 || !ray.hasHit() ||
      std::abs(ray.m_hitPointWorld.y() - 4) > 1e-4) {
    std::fprintf(stderr, "consumer (bullet): resting at %.4f m, ray hit %d\n", rest, ray.hasHit());
    return 1;
  }
  std::printf("consumer (bullet): a sphere rests at %.4f m, the ray hits at %.4f m\n", rest,
              double(ray.m_hitPointWorld.y()));
  return 0;
}
