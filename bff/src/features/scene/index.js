// Scene: a live 3D view of the cell. Each arm is drawn from its URDF (a file or a ROS parameter, served with its
// meshes by /api/scene/...) and moved by its group's joint states; the parts come from a MarkerArray; with a
// fixed frame, arm bases and marker frames come from TF. Read only:
// no commands, nothing that moves the robot.
import { defineFeature, featureSchema } from '../../core/features/feature.js';
import { armSpecs, checkScene, urdfUrl } from './arms.js';
import { sceneRoutes, sceneOpenApiPaths } from './routes.js';

export { armSpecs, checkScene, urdfFileProblems, urdfUrl, DEFAULT_JOINT_STATES } from './arms.js';
export { sceneRoutes, sceneOpenApiPaths } from './routes.js';
export { SceneError, getParam, parseMethodResponse, prepareUrdf, meshPath, meshName, meshType, findPackage } from './urdf.js';

/** The standard TF topics (tf2_msgs/TFMessage) the view reads when the cell file gives scene.fixed_frame. */
export const TF_TOPICS = ['/tf', '/tf_static'];

/** Default seconds after which an arm's joint states count as stale (the arm greyed out). */
export const DEFAULT_STALE_AFTER_S = 1;

export default defineFeature({
  id: 'scene',
  title: '3D view',
  schema: featureSchema('scene'),
  check: (section, cell) => checkScene(section, cell),
  // Where each arm's URDF comes from stays on the robot PC: the app gets the URL that serves it.
  view: (section, role, cell) => ({
    markers: section.markers ?? null,
    fixed_frame: section.fixed_frame ?? null,
    stale_after_s: section.stale_after_s ?? DEFAULT_STALE_AFTER_S,
    arms: armSpecs(section, cell).map((a) => ({
      group: a.group, joints: a.joints, joint_states: a.joint_states, base: a.base, base_frame: a.base_frame, urdf_url: urdfUrl(a.group),
    })),
  }),
  reads: (section, cell) => ({
    subscribe: [
      ...new Set(armSpecs(section, cell).map((a) => a.joint_states)),
      ...(section.markers ? [section.markers] : []),
      ...(section.fixed_frame ? TF_TOPICS : []),
    ],
  }),
  routes: ({ section, cell, cellFile, env, guard, log }) => sceneRoutes({ section, cell, cellFile, env, guard, log }),
  openapi: sceneOpenApiPaths,
});
