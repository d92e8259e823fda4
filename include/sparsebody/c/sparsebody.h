/* sparsebody C API: full-body avatars from a VR headset and two controllers (optionally a pelvis
 * tracker), for C, C# (examples/unity/Sparsebody.cs) and any language with a C FFI.
 * Pure C99. The implementation is include/sparsebody/c/sparsebody_c_impl.hpp: the shared library
 * sparsebody_c (CMake target sparsebody::c), or compiled into one C++17 TU of your own (define
 * SPARSEBODY_C_STATIC there and wherever this header is included).
 *
 * Use:
 *   sb_weights* w;  sb_weights_load(SB_MODEL_N3P, "examples/weights/n3p", &w);   once, any thread
 *   sb_pipeline_config c;  sb_pipeline_config_init(&c, SB_PIPELINE_N3P_DIRECT);
 *   sb_pipeline* p;  sb_pipeline_create(w, &c, &p);                                 one per avatar
 *   per frame:  sb_pipeline_push(p, &frame, NULL);  sb_pipeline_read(p, &info, rot, pos, n);
 *   sb_pipeline_destroy(p);  sb_weights_destroy(w);      (either order: a pipeline keeps its weights)
 * Many avatars on one weight set: sb_crowd_create / sb_crowd_push (all users' frames in one call) /
 * sb_crowd_user (each user's sb_pipeline handle, for reading).
 *
 * Errors: every call returns an sb_status: 0 OK, > 0 success with a note, < 0 an error that changed
 * nothing. sb_last_error(handle) is the one-line message of the last failed (or noted) call on that
 * handle; sb_last_error(NULL) that of the last one on this thread (creation failures, bad handles).
 * No C++ exception ever leaves a call. NULL, foreign or destroyed handles (each handle carries a tag),
 * a struct_size that is not this header's sizeof, NaN input, a too small array and calls out of
 * order give an error code, never a crash (a pointer to unreadable memory cannot be detected).
 *
 * Threads: an sb_weights is immutable after loading: any number of threads may create pipelines
 * from it at once. An sb_pipeline is used by one thread at a time (no locks inside: serialise
 * yourself if you share one); it may move between threads. Different pipelines run in parallel.
 * sb_last_error(p) is valid until the next call on p; sb_last_error(NULL) until the next failing call
 * on this thread. Per frame (push, read, the queries) there is no allocation, no lock, no exception
 * (the C library's thread-local message buffer: the loader may allocate it on a thread's first error).
 *
 * Conventions (OpenXR): positions in metres, quaternions stored x y z w (XrPosef's layout: orientation
 * then position), right-handed, +Y up, -Z forward, floor at y = 0 (XR_REFERENCE_SPACE_TYPE_STAGE).
 * Output: the standard skeleton (sb_pipeline_joint_name/parents), positions in the user's size. */
#ifndef SPARSEBODY_C_SPARSEBODY_H
#define SPARSEBODY_C_SPARSEBODY_H

#include <stdint.h>

#if defined(SPARSEBODY_C_STATIC)
#define SPARSEBODY_API
#elif defined(_WIN32)
#ifdef SPARSEBODY_C_BUILD
#define SPARSEBODY_API __declspec(dllexport)
#else
#define SPARSEBODY_API __declspec(dllimport)
#endif
#elif defined(__GNUC__)
#define SPARSEBODY_API __attribute__((visibility("default")))
#else
#define SPARSEBODY_API
#endif

#ifdef __cplusplus
extern "C" {
#endif

/* Version of this header's structs and calls; sb_pipeline_config.version must be it. */
#define SB_API_VERSION 1u

typedef enum sb_status {
  SB_OK = 0,
  SB_NO_POSE = 1,             /* read: pushed, but no pose yet (no valid headset frame so far) */
  SB_NONFINITE_POSE = 2,      /* push: a tracker flagged valid had NaN/Inf: treated as lost this frame */
  SB_ERR_NULL = -1,           /* a required pointer argument is NULL */
  SB_ERR_BAD_HANDLE = -2,     /* not a live handle of the expected type (foreign, destroyed) */
  SB_ERR_STRUCT_SIZE = -3,    /* struct_size is not this header's sizeof, or version unknown */
  SB_ERR_INVALID_ARGUMENT = -4, /* NaN time, unknown enum, out-of-range value, unusable frame */
  SB_ERR_CAPACITY = -5,       /* the caller's array is smaller than the joint count */
  SB_ERR_ORDER = -6,          /* call out of order (read before the first push) */
  SB_ERR_LOAD = -7,           /* a weights file missing or malformed (message names it) */
  SB_ERR_NO_TRAINED_WEIGHTS = -8, /* no longer returned (QuestSim runs through this API); kept for old callers */
  SB_ERR_UNSUPPORTED = -9,    /* e.g. weights whose network sizes this build does not include */
  SB_ERR_MISMATCH = -10,      /* weights of another model than the pipeline needs */
  SB_ERR_OUT_OF_MEMORY = -11,
  SB_ERR_INTERNAL = -12       /* an unexpected C++ exception, caught */
} sb_status;

/* Weight sets (sb_weights_load). */
typedef enum sb_model {
  SB_MODEL_LOBSTR = 1,   /* one file, e.g. examples/weights/lobstr_compact.weights.json (H 256, latent 128) */
  SB_MODEL_N3P = 2,      /* Neural3Points: three files PREFIX_upper/_lower/_signal.json */
  SB_MODEL_QUESTSIM = 3  /* one file, e.g. examples/weights/questsim_policy.json (kind questsim_policy) */
} sb_model;

/* How a weight set is stored in memory (sb_weights_load_storage). The files are float JSON either way:
 * f16 and int8 are made at load time. AUTO: the fastest for the CPU this library was built for
 * (int8 wherever it has a SIMD int8 kernel: AVX2, AVX-VNNI, AVX-512 VNNI, NEON; else float).
 * int8 is approximate (per-row weight scales, per-step input scales: nn/int8.hpp); f16 rounds weights
 * to half precision. */
typedef enum sb_storage {
  SB_STORAGE_AUTO = 0,
  SB_STORAGE_FLOAT = 1,
  SB_STORAGE_F16 = 2,
  SB_STORAGE_INT8 = 3
} sb_storage;

typedef enum sb_pipeline_kind {
  SB_PIPELINE_LOBSTR = 1,      /* SB_MODEL_LOBSTR weights; needs the pelvis tracker */
  SB_PIPELINE_N3P_DIRECT = 2,  /* SB_MODEL_N3P weights; headset + controllers */
  SB_PIPELINE_N3P_PHYSICS = 3, /* SB_MODEL_N3P weights (shipped for it: examples/weights/n3p_physics, the predictor its
                                  controller was tuned with); simulated avatar, output 0.1 s behind */
  SB_PIPELINE_QUESTSIM = 4     /* SB_MODEL_QUESTSIM weights; headset + controllers; torque policy on a simulated
                                  avatar sized by the calibration's stature, output 0.17 s behind; contact_ik unused */
} sb_pipeline_kind;

/* Tracker indices and the validity bits of sb_tracker_frame.valid. */
enum { SB_TRACKER_HEAD = 0, SB_TRACKER_LEFT_HAND = 1, SB_TRACKER_RIGHT_HAND = 2, SB_TRACKER_PELVIS = 3, SB_TRACKER_COUNT = 4 };
#define SB_VALID_HEAD 1u
#define SB_VALID_LEFT_HAND 2u
#define SB_VALID_RIGHT_HAND 4u
#define SB_VALID_PELVIS 8u

/* sb_pose_info.flags */
#define SB_POSE_OK 1u          /* a pose is available (what sb_pipeline_read copied) */
#define SB_POSE_CALIBRATING 2u /* not calibrated: the default body (searching, or auto_calibration 0), or refused */
#define SB_POSE_RESET 4u       /* the model restarted during the last push (tracking gap, origin jump, start) */
#define SB_POSE_FALLEN 8u      /* physics: the avatar fell during the last push and was reset (N3P: to the prediction; QuestSim: standing under the headset) */

/* sb_calibration_report.state / .source */
enum { SB_CALIBRATION_DEFAULT = 0, SB_CALIBRATION_CALIBRATED = 1, SB_CALIBRATION_REFUSED = 2 };
enum { SB_CALIBRATION_SOURCE_NONE = 0, SB_CALIBRATION_SOURCE_AUTOMATIC = 1, SB_CALIBRATION_SOURCE_EXPLICIT = 2,
       SB_CALIBRATION_SOURCE_APPLICATION = 3 };

typedef struct sb_quatf { float x, y, z, w; } sb_quatf;
typedef struct sb_vec3f { float x, y, z; } sb_vec3f;
typedef struct sb_posef { sb_quatf orientation; sb_vec3f position; } sb_posef; /* = XrPosef, 28 bytes */

/* One input frame at any rate (the pipeline resamples to its model rate). */
typedef struct sb_tracker_frame {
  uint32_t struct_size;              /* sizeof(sb_tracker_frame) */
  uint32_t valid;                    /* SB_VALID_* bits: position and orientation both tracked */
  double time;                       /* seconds, any origin, increasing; must be finite */
  sb_posef pose[SB_TRACKER_COUNT];   /* head (the view pose), left grip, right grip, pelvis */
} sb_tracker_frame;

typedef struct sb_pipeline_config {
  uint32_t struct_size;      /* sizeof(sb_pipeline_config) */
  uint32_t version;          /* SB_API_VERSION */
  int32_t pipeline;          /* sb_pipeline_kind */
  int32_t auto_calibration;  /* 1 (default): calibrate from standing windows; 0: default body until an explicit call */
  int32_t contact_ik;        /* 1 (default): foot-contact IK (LoBSTr contact IK, Neural3Points foot pinning) */
  int32_t window_mode;       /* LoBSTr: 1 re-runs the last second each frame (the paper's inference); 0 (default) streams */
} sb_pipeline_config;

/* What sb_pipeline_read reports beside the arrays. */
typedef struct sb_pose_info {
  uint32_t struct_size;  /* sizeof(sb_pose_info) */
  uint32_t flags;        /* SB_POSE_* */
  double time;           /* s, input clock: the input time the pose shows (physics: 0.1 s behind the last push) */
  int64_t frames;        /* model frames stepped since creation or reset */
  int32_t steps;         /* model steps the last push ran */
  int32_t joint_count;
  sb_posef root;         /* root joint: world orientation and position (user's size) */
  float user_scale;      /* user's size / the standard skeleton's */
  int32_t contact[2];    /* left, right foot in contact (0/1) */
} sb_pose_info;

typedef struct sb_calibration_report {
  uint32_t struct_size;  /* sizeof(sb_calibration_report) */
  int32_t state;         /* SB_CALIBRATION_DEFAULT / CALIBRATED / REFUSED */
  int32_t source;        /* SB_CALIBRATION_SOURCE_* */
  int32_t windows;       /* standing windows averaged */
  int64_t frames_used;   /* model frames of the (newest) window taken; 0 when none */
  double stature;        /* m */
  double eye_height;     /* m above the floor */
  double scale;          /* s: user -> standard skeleton */
  double floor;          /* world y of the floor */
  double confidence;     /* [0, 1] */
  double first_time, last_time; /* s, input clock, of the window (NaN when none) */
  char message[192];     /* one line, NUL-terminated */
  /* 1 while that controller (0 left, 1 right) still has the device model's grip offset: no standing
   * window has seen it held (e.g. the controllers lay on a table at the first stand). */
  int32_t grip_default[2];
  int32_t grips_not_held; /* standing windows whose controllers were not held (their grips not taken) */
} sb_calibration_report;

typedef struct sb_weights sb_weights;
typedef struct sb_pipeline sb_pipeline;

SPARSEBODY_API uint32_t sb_api_version(void);
SPARSEBODY_API const char* sb_status_name(sb_status s); /* "SB_OK", ...; "unknown" otherwise */
/* One-line message of the last failed or noted call on `handle` (an sb_weights*, sb_pipeline* or sb_crowd*);
 * NULL or anything that is not a live handle: the last one on this thread. Never NULL. */
SPARSEBODY_API const char* sb_last_error(const void* handle);

/* --- weights: loaded once, shared read-only ------------------------------------------------- */
/* SB_MODEL_LOBSTR: path of the weights file. SB_MODEL_N3P: a prefix ("dir/n3p" for
 * dir/n3p_upper.json ...), one of the three files, or a directory holding n3p_*.json.
 * *out is NULL on failure. */
SPARSEBODY_API sb_status sb_weights_load(int32_t model, const char* path, sb_weights** out);
/* The same with a storage (sb_storage; sb_weights_load is SB_STORAGE_FLOAT). LoBSTr and Neural3Points
 * (every pipeline made from them, crowds too) take any; QuestSim float only (AUTO gives float,
 * F16 / INT8 are SB_ERR_UNSUPPORTED). sb_weights_storage tells the storage taken (AUTO resolved). */
SPARSEBODY_API sb_status sb_weights_load_storage(int32_t model, const char* path, int32_t storage, sb_weights** out);
SPARSEBODY_API sb_status sb_weights_storage(const sb_weights* w, int32_t* storage);
/* Neural3Points from three explicit paths. */
SPARSEBODY_API sb_status sb_weights_load_n3p(const char* upper, const char* lower, const char* signal, sb_weights** out);
SPARSEBODY_API sb_status sb_weights_model(const sb_weights* w, int32_t* model);
/* NULL is a no-op (SB_OK). Pipelines created from w keep working. */
SPARSEBODY_API sb_status sb_weights_destroy(sb_weights* w);

/* --- pipelines: one per avatar ---------------------------------------------------------------- */
/* The defaults for `pipeline` (sets struct_size and version). */
SPARSEBODY_API sb_status sb_pipeline_config_init(sb_pipeline_config* cfg, int32_t pipeline);
SPARSEBODY_API sb_status sb_pipeline_create(const sb_weights* w, const sb_pipeline_config* cfg, sb_pipeline** out);
SPARSEBODY_API sb_status sb_pipeline_destroy(sb_pipeline* p); /* NULL is a no-op (SB_OK) */
/* Back to the created state (an explicit calibration is kept, an automatic one forgotten). */
SPARSEBODY_API sb_status sb_pipeline_reset(sb_pipeline* p);

/* Per frame. `steps` (may be NULL): model steps run (0 when the frame falls between ticks).
 * SB_NONFINITE_POSE: the frame was used, the named tracker as lost. */
SPARSEBODY_API sb_status sb_pipeline_push(sb_pipeline* p, const sb_tracker_frame* frame, int32_t* steps);
/* The current pose: info (required); local_rotations (joint local rotations, joint 0's is the root's
 * world orientation) and world_positions (user's size) may each be NULL; capacity is their length
 * in elements and must be >= the joint count when either is given. SB_NO_POSE: info is filled,
 * the arrays are untouched. SB_ERR_ORDER before the first push (after create or reset). */
SPARSEBODY_API sb_status sb_pipeline_read(sb_pipeline* p, sb_pose_info* info, sb_quatf* local_rotations, sb_vec3f* world_positions,
                                          int32_t capacity);

/* The skeleton of the output. Names stay valid as long as p. */
SPARSEBODY_API sb_status sb_pipeline_joint_count(sb_pipeline* p, int32_t* count);
SPARSEBODY_API sb_status sb_pipeline_joint_name(sb_pipeline* p, int32_t joint, const char** name);
SPARSEBODY_API sb_status sb_pipeline_joint_parents(sb_pipeline* p, int32_t* parents, int32_t capacity); /* root: -1 */
SPARSEBODY_API sb_status sb_pipeline_frame_rate(sb_pipeline* p, double* fps); /* model frames per second */

/* --- calibration ------------------------------------------------------------------------------- */
/* Forget the calibration (explicit or automatic) and search for standing windows again. */
SPARSEBODY_API sb_status sb_pipeline_recalibrate(sb_pipeline* p);
/* Explicit calibration from one frame of the user upright facing forward (a T-pose or standing);
 * SB_ERR_INVALID_ARGUMENT (unchanged) when it cannot be used. Stops the search until recalibrate. */
SPARSEBODY_API sb_status sb_pipeline_calibrate_frame(sb_pipeline* p, const sb_tracker_frame* frame);
/* Explicit calibration for trackers that are at the joints already (mocap synthesis, the demo's
 * BVH input): no device or orientation offsets, only the size, scale = standard skeleton / user
 * (e.g. the ratio of leg lengths), in (0.1, 10). Stops the automatic search until recalibrate. */
SPARSEBODY_API sb_status sb_pipeline_set_joint_calibration(sb_pipeline* p, double scale);
SPARSEBODY_API sb_status sb_pipeline_calibration(sb_pipeline* p, sb_calibration_report* report);

/* --- what the tracker stream found ------------------------------------------------------------- */
/* Since creation: recentred tracking spaces (every tracker turned / shifted together between two
 * frames; each restarted the model there) and the times the left and right controllers were found in
 * the other hands and exchanged (symmetric controllers whose roles the runtime gave the wrong way
 * round); controllers_swapped: 1 while they are exchanged, else 0 (sb_pipeline_reset forgets it).
 * SB_ERR_NULL when any pointer is NULL. */
SPARSEBODY_API sb_status sb_pipeline_stream_events(sb_pipeline* p, int32_t* recentres, int32_t* controller_swaps,
                                                   int32_t* controllers_swapped);
/* Since creation: stand-ups found (the headset rose by more than 0.25 m, in place, from a rest of
 * 2 s: the user stood up from a seat). Each restarted the model there, and for 1 s the feet follow it
 * unheld (LoBSTr, Neural3Points direct and physics; README "Sitting down and standing up"). QuestSim
 * has no detector: 0. SB_ERR_NULL when stand_ups is NULL. */
SPARSEBODY_API sb_status sb_pipeline_stand_ups(sb_pipeline* p, int64_t* stand_ups);

/* --- crowds: many avatars stepped together ------------------------------------------------------ */
/* A crowd is `users` (1-64) avatars of SB_PIPELINE_LOBSTR or SB_PIPELINE_N3P_DIRECT on one weight set
 * (a social scene). Each user has its own tracker stream, calibration and state; at each model tick the
 * users' networks run in one call, so each weight matrix is read once for all of them. Every user gets
 * exactly what a pipeline of its own (same weights, same cfg, same frames) would give.
 * Threads: as an sb_pipeline (one thread at a time), its users' handles included. */
typedef struct sb_crowd sb_crowd;
SPARSEBODY_API sb_status sb_crowd_create(const sb_weights* w, const sb_pipeline_config* cfg, int32_t users, sb_crowd** out);
/* NULL is a no-op (SB_OK). Its users' handles die with it. */
SPARSEBODY_API sb_status sb_crowd_destroy(sb_crowd* c);
SPARSEBODY_API sb_status sb_crowd_size(sb_crowd* c, int32_t* users);
/* One frame per user: frames[i] is user i's; count must be the crowd's size. A user with no new frame
 * this time gets its last one again (the same time completes no tick and changes nothing).
 * steps (may be NULL): count entries, the model steps each user ran. Every frame is checked first: one
 * that sb_pipeline_push would refuse refuses the call (nothing pushed; the message names the user).
 * SB_NONFINITE_POSE as sb_pipeline_push (the message names the first such user). */
SPARSEBODY_API sb_status sb_crowd_push(sb_crowd* c, const sb_tracker_frame* frames, int32_t count, int32_t* steps);
/* User i's pipeline handle, owned by the crowd and valid until sb_crowd_destroy. Every sb_pipeline_*
 * call works on it (read, calibration, reset, stream events, skeleton); sb_pipeline_push steps that
 * user alone, as the crowd would; sb_pipeline_destroy refuses it (SB_ERR_INVALID_ARGUMENT). */
SPARSEBODY_API sb_status sb_crowd_user(sb_crowd* c, int32_t i, sb_pipeline** user);

#ifdef __cplusplus
}
#endif
#endif /* SPARSEBODY_C_SPARSEBODY_H */
