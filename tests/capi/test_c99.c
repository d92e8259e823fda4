/* The header is plain C99 (compiled with -std=c99 -pedantic -Werror), and the shared library
 * works from C: load the shipped weights, stream a standing headset for a second, read the pose.
 * Usage: capi_c99 WEIGHTS_DIR. Exit 0 on success. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "sparsebody/c/sparsebody.h"

static int fails = 0;
#define EXPECT(c)                                                          \
  do {                                                                     \
    if (!(c)) {                                                            \
      fprintf(stderr, "%s:%d: failed: %s\n", __FILE__, __LINE__, #c);      \
      ++fails;                                                             \
    }                                                                      \
  } while (0)

int main(int argc, char** argv) {
  char path[1024];
  sb_weights* w = NULL;
  sb_pipeline* p = NULL;
  sb_pipeline_config cfg;
  sb_tracker_frame f;
  sb_pose_info info;
  sb_quatf rot[64];
  sb_vec3f pos[64];
  int32_t n = 0, i;
  const char* name = NULL;
  if (argc != 2) return 2;
  snprintf(path, sizeof path, "%s/n3p", argv[1]);
  EXPECT(sb_weights_load(SB_MODEL_N3P, path, &w) == SB_OK);
  EXPECT(sb_pipeline_config_init(&cfg, SB_PIPELINE_N3P_DIRECT) == SB_OK);
  EXPECT(sb_pipeline_create(w, &cfg, &p) == SB_OK);
  EXPECT(sb_pipeline_joint_count(p, &n) == SB_OK && n > 0 && n <= 64);
  EXPECT(sb_pipeline_joint_name(p, 0, &name) == SB_OK && name && strlen(name) > 0);
  memset(&info, 0, sizeof info);
  info.struct_size = sizeof info;
  EXPECT(sb_pipeline_read(p, &info, rot, pos, 64) == SB_ERR_ORDER);
  EXPECT(strlen(sb_last_error(p)) > 0);
  memset(&f, 0, sizeof f);
  f.struct_size = sizeof f;
  f.valid = SB_VALID_HEAD | SB_VALID_LEFT_HAND | SB_VALID_RIGHT_HAND;
  for (i = 0; i < SB_TRACKER_COUNT; ++i) f.pose[i].orientation.w = 1.0f;  /* looking along -Z */
  f.pose[SB_TRACKER_HEAD].position.y = 1.62f;
  f.pose[SB_TRACKER_LEFT_HAND].position.x = -0.2f;
  f.pose[SB_TRACKER_LEFT_HAND].position.y = 0.85f;
  f.pose[SB_TRACKER_RIGHT_HAND].position.x = 0.2f;
  f.pose[SB_TRACKER_RIGHT_HAND].position.y = 0.85f;
  for (i = 0; i < 72; ++i) {
    f.time = i / 72.0;
    EXPECT(sb_pipeline_push(p, &f, NULL) == SB_OK);
  }
  EXPECT(sb_pipeline_read(p, &info, rot, pos, 64) == SB_OK);
  EXPECT(info.flags & SB_POSE_OK);
  EXPECT(isfinite(pos[0].y) && pos[0].y > 0.5f && pos[0].y < 1.5f); /* the hips of someone standing */
  f.time = NAN;
  EXPECT(sb_pipeline_push(p, &f, NULL) == SB_ERR_INVALID_ARGUMENT);
  EXPECT(sb_pipeline_destroy(p) == SB_OK);
  EXPECT(sb_pipeline_push(p, &f, NULL) == SB_ERR_BAD_HANDLE);
  EXPECT(sb_weights_destroy(w) == SB_OK);
  printf("capi_c99: %d joints, hips at y = %.3f m, %d failures\n", (int)n, (double)pos[0].y, fails);
  return fails ? 1 : 0;
}
