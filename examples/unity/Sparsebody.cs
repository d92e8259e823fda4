// sparsebody for C# / Unity: P/Invoke over the C API (include/sparsebody/c/sparsebody.h), one file.
// Ship it with the native library (libsparsebody_c.so / sparsebody_c.dll / libsparsebody_c.dylib,
// built by the CMake target sparsebody_c) in the package's Plugins folder. The structs are
// blittable and laid out as the header's (LayoutKind.Sequential); CalibrationReport holds a fixed
// byte buffer, so the file needs "Allow unsafe code" (mcs -unsafe).
//
//   using (var w = Sparsebody.Weights.Load(Sparsebody.Model.N3P, "examples/weights/n3p"))
//   using (var p = new Sparsebody.Pipeline(w, Sparsebody.PipelineKind.N3PDirect)) {
//     var rot = new Sparsebody.Quatf[p.JointCount]; var pos = new Sparsebody.Vec3f[p.JointCount];
//     every frame: p.Push(ref frame); if (p.Read(rot, pos, out var info)) { ... }
//   }
//
// Many avatars on one weight set: new Sparsebody.Crowd(w, kind, n); crowd.Push(frames); crowd.Users[i].Read(...).
// Errors: a failing call throws SparsebodyException (its Status and the library's one-line message).
// Per frame (Push, Read) nothing is allocated on the managed side either: the arrays are pinned, not
// copied. Threads: as the header says, a Weights may be shared by pipelines on any threads; a
// Pipeline is used by one thread at a time.
// Conventions: OpenXR (+Y up, -Z forward, metres, quaternions x y z w). Unity is left-handed
// (+Z forward): convert with position (x, y, -z) and rotation (-x, -y, z, w) on the way in and out.
using System;
using System.Runtime.InteropServices;

namespace Sparsebody {

public enum Status : int {
  Ok = 0, NoPose = 1, NonfinitePose = 2,
  ErrNull = -1, ErrBadHandle = -2, ErrStructSize = -3, ErrInvalidArgument = -4, ErrCapacity = -5, ErrOrder = -6,
  ErrLoad = -7, ErrNoTrainedWeights = -8, ErrUnsupported = -9, ErrMismatch = -10, ErrOutOfMemory = -11, ErrInternal = -12,
}

public enum Model : int { LoBSTr = 1, N3P = 2, QuestSim = 3 }
// How weights are stored in memory: Auto picks int8 where the library's build has a SIMD int8 kernel
// (AVX2, NEON on headsets), else float. LoBSTr and N3P take any; QuestSim float only.
public enum Storage : int { Auto = 0, Float = 1, F16 = 2, Int8 = 3 }
public enum PipelineKind : int { LoBSTr = 1, N3PDirect = 2, N3PPhysics = 3, QuestSim = 4 }

[Flags]
public enum TrackerValid : uint { None = 0, Head = 1, LeftHand = 2, RightHand = 4, Pelvis = 8 }

[Flags]
public enum PoseFlags : uint { None = 0, Ok = 1, Calibrating = 2, Reset = 4, Fallen = 8 }

public enum CalibrationState : int { Default = 0, Calibrated = 1, Refused = 2 }
public enum CalibrationSource : int { None = 0, Automatic = 1, Explicit = 2, Application = 3 }

[StructLayout(LayoutKind.Sequential)]
public struct Quatf { public float x, y, z, w; }

[StructLayout(LayoutKind.Sequential)]
public struct Vec3f { public float x, y, z; }

[StructLayout(LayoutKind.Sequential)]
public struct Posef { public Quatf orientation; public Vec3f position; }  // = XrPosef

[StructLayout(LayoutKind.Sequential)]
public struct TrackerFrame {
  public uint structSize;
  public TrackerValid valid;
  public double time;  // seconds, increasing
  public Posef head, leftHand, rightHand, pelvis;
  public static TrackerFrame Create() {
    var f = new TrackerFrame();
    f.structSize = (uint)Marshal.SizeOf(typeof(TrackerFrame));
    f.head.orientation.w = f.leftHand.orientation.w = f.rightHand.orientation.w = f.pelvis.orientation.w = 1;
    return f;
  }
}

[StructLayout(LayoutKind.Sequential)]
public struct PipelineConfig {
  public uint structSize, version;
  public PipelineKind pipeline;
  public int autoCalibration, contactIK, windowMode;  // 0 / 1
}

[StructLayout(LayoutKind.Sequential)]
public struct PoseInfo {
  public uint structSize;
  public PoseFlags flags;
  public double time;   // input time the pose shows
  public long frames;
  public int steps, jointCount;
  public Posef root;    // world, user's size
  public float userScale;
  public int contactLeft, contactRight;
}

[StructLayout(LayoutKind.Sequential)]
public unsafe struct CalibrationReport {
  public uint structSize;
  public CalibrationState state;
  public CalibrationSource source;
  public int windows;
  public long framesUsed;
  public double stature, eyeHeight, scale, floor, confidence, firstTime, lastTime;
  public fixed byte message[192];
  public fixed int gripDefault[2];  // 1 while that controller (0 left, 1 right) has the device model's grip offset
  public int gripsNotHeld;          // standing windows whose controllers were not held
  public string Message {
    get { fixed (byte* m = message) return Marshal.PtrToStringAnsi((IntPtr)m); }
  }
}

public class SparsebodyException : Exception {
  public readonly Status Status;
  public SparsebodyException(Status s, string message) : base(s + ": " + message) { Status = s; }
}

// The C entry points, one to one.
public static class Native {
#if UNITY_IOS && !UNITY_EDITOR
  public const string Lib = "__Internal";  // iOS links native plugins statically
#else
  public const string Lib = "sparsebody_c";  // libsparsebody_c.so / sparsebody_c.dll / libsparsebody_c.dylib
#endif
  public const uint ApiVersion = 1;
  [DllImport(Lib, CallingConvention = CallingConvention.Cdecl)] public static extern uint sb_api_version();
  [DllImport(Lib, CallingConvention = CallingConvention.Cdecl)] public static extern IntPtr sb_last_error(IntPtr handle);
  [DllImport(Lib, CallingConvention = CallingConvention.Cdecl)] public static extern IntPtr sb_last_error(WeightsHandle handle);
  [DllImport(Lib, CallingConvention = CallingConvention.Cdecl)] public static extern IntPtr sb_last_error(PipelineHandle handle);
  [DllImport(Lib, CallingConvention = CallingConvention.Cdecl)] public static extern IntPtr sb_last_error(CrowdHandle handle);
  [DllImport(Lib, CallingConvention = CallingConvention.Cdecl)]
  public static extern Status sb_weights_load(Model model, [MarshalAs(UnmanagedType.LPStr)] string path, out WeightsHandle w);
  [DllImport(Lib, CallingConvention = CallingConvention.Cdecl)]
  public static extern Status sb_weights_load_storage(Model model, [MarshalAs(UnmanagedType.LPStr)] string path, Storage storage, out WeightsHandle w);
  [DllImport(Lib, CallingConvention = CallingConvention.Cdecl)] public static extern Status sb_weights_storage(WeightsHandle w, out Storage storage);
  [DllImport(Lib, CallingConvention = CallingConvention.Cdecl)]
  public static extern Status sb_weights_load_n3p([MarshalAs(UnmanagedType.LPStr)] string upper, [MarshalAs(UnmanagedType.LPStr)] string lower,
                                                  [MarshalAs(UnmanagedType.LPStr)] string signal, out WeightsHandle w);
  [DllImport(Lib, CallingConvention = CallingConvention.Cdecl)] public static extern Status sb_weights_destroy(IntPtr w);
  [DllImport(Lib, CallingConvention = CallingConvention.Cdecl)] public static extern Status sb_pipeline_config_init(out PipelineConfig cfg, PipelineKind kind);
  [DllImport(Lib, CallingConvention = CallingConvention.Cdecl)]
  public static extern Status sb_pipeline_create(WeightsHandle w, ref PipelineConfig cfg, out PipelineHandle p);
  [DllImport(Lib, CallingConvention = CallingConvention.Cdecl)] public static extern Status sb_pipeline_destroy(IntPtr p);
  [DllImport(Lib, CallingConvention = CallingConvention.Cdecl)] public static extern Status sb_pipeline_reset(PipelineHandle p);
  [DllImport(Lib, CallingConvention = CallingConvention.Cdecl)]
  public static extern Status sb_pipeline_push(PipelineHandle p, ref TrackerFrame f, out int steps);
  [DllImport(Lib, CallingConvention = CallingConvention.Cdecl)]
  public static extern Status sb_pipeline_read(PipelineHandle p, ref PoseInfo info, [In, Out] Quatf[] rot, [In, Out] Vec3f[] pos, int capacity);
  [DllImport(Lib, CallingConvention = CallingConvention.Cdecl)] public static extern Status sb_pipeline_joint_count(PipelineHandle p, out int n);
  [DllImport(Lib, CallingConvention = CallingConvention.Cdecl)] public static extern Status sb_pipeline_joint_name(PipelineHandle p, int joint, out IntPtr name);
  [DllImport(Lib, CallingConvention = CallingConvention.Cdecl)]
  public static extern Status sb_pipeline_joint_parents(PipelineHandle p, [Out] int[] parents, int capacity);
  [DllImport(Lib, CallingConvention = CallingConvention.Cdecl)] public static extern Status sb_pipeline_frame_rate(PipelineHandle p, out double fps);
  [DllImport(Lib, CallingConvention = CallingConvention.Cdecl)] public static extern Status sb_pipeline_recalibrate(PipelineHandle p);
  [DllImport(Lib, CallingConvention = CallingConvention.Cdecl)] public static extern Status sb_pipeline_stream_events(PipelineHandle p, out int recentres, out int controllerSwaps, out int controllersSwapped);
  [DllImport(Lib, CallingConvention = CallingConvention.Cdecl)] public static extern Status sb_pipeline_stand_ups(PipelineHandle p, out long standUps);
  [DllImport(Lib, CallingConvention = CallingConvention.Cdecl)] public static extern Status sb_pipeline_calibrate_frame(PipelineHandle p, ref TrackerFrame f);
  [DllImport(Lib, CallingConvention = CallingConvention.Cdecl)] public static extern Status sb_pipeline_set_joint_calibration(PipelineHandle p, double scale);
  [DllImport(Lib, CallingConvention = CallingConvention.Cdecl)] public static extern Status sb_pipeline_calibration(PipelineHandle p, ref CalibrationReport r);
  [DllImport(Lib, CallingConvention = CallingConvention.Cdecl)]
  public static extern Status sb_crowd_create(WeightsHandle w, ref PipelineConfig cfg, int users, out CrowdHandle c);
  [DllImport(Lib, CallingConvention = CallingConvention.Cdecl)] public static extern Status sb_crowd_destroy(IntPtr c);
  [DllImport(Lib, CallingConvention = CallingConvention.Cdecl)]
  public static extern Status sb_crowd_push(CrowdHandle c, [In] TrackerFrame[] frames, int count, [Out] int[] steps);
  [DllImport(Lib, CallingConvention = CallingConvention.Cdecl)] public static extern Status sb_crowd_user(CrowdHandle c, int i, out IntPtr user);
}

public sealed class WeightsHandle : SafeHandle {
  WeightsHandle() : base(IntPtr.Zero, true) {}
  public override bool IsInvalid { get { return handle == IntPtr.Zero; } }
  protected override bool ReleaseHandle() { return Native.sb_weights_destroy(handle) == Status.Ok; }
}

public sealed class PipelineHandle : SafeHandle {
  PipelineHandle() : base(IntPtr.Zero, true) {}
  // A crowd's user: the crowd frees it (ownsHandle false).
  internal PipelineHandle(IntPtr user) : base(IntPtr.Zero, false) { SetHandle(user); }
  public override bool IsInvalid { get { return handle == IntPtr.Zero; } }
  protected override bool ReleaseHandle() { return Native.sb_pipeline_destroy(handle) == Status.Ok; }
}

public sealed class CrowdHandle : SafeHandle {
  CrowdHandle() : base(IntPtr.Zero, true) {}
  public override bool IsInvalid { get { return handle == IntPtr.Zero; } }
  protected override bool ReleaseHandle() { return Native.sb_crowd_destroy(handle) == Status.Ok; }
}

// A weight set, loaded once; any number of pipelines (on any threads) share it, and keep it alive.
public sealed class Weights : IDisposable {
  public readonly WeightsHandle Handle;
  public readonly Model Model;
  Weights(WeightsHandle h, Model m) { Handle = h; Model = m; }

  // LoBSTr: the weights file; N3P: a prefix ("dir/n3p"), one of its three files or their directory.
  public static Weights Load(Model model, string path) { return Load(model, path, Storage.Float); }
  public static Weights Load(Model model, string path, Storage storage) {
    WeightsHandle h;
    Status s = Native.sb_weights_load_storage(model, path, storage, out h);
    if (s < 0) throw new SparsebodyException(s, Marshal.PtrToStringAnsi(Native.sb_last_error(IntPtr.Zero)));
    return new Weights(h, model);
  }
  // The storage taken (Auto resolved).
  public Storage Storage {
    get {
      Storage s;
      Status st = Native.sb_weights_storage(Handle, out s);
      if (st < 0) throw new SparsebodyException(st, Marshal.PtrToStringAnsi(Native.sb_last_error(IntPtr.Zero)));
      return s;
    }
  }
  public static Weights LoadN3P(string upper, string lower, string signal) {
    WeightsHandle h;
    Status s = Native.sb_weights_load_n3p(upper, lower, signal, out h);
    if (s < 0) throw new SparsebodyException(s, Marshal.PtrToStringAnsi(Native.sb_last_error(IntPtr.Zero)));
    return new Weights(h, Model.N3P);
  }
  public void Dispose() { Handle.Dispose(); }
}

// One avatar.
public sealed class Pipeline : IDisposable {
  public readonly PipelineHandle Handle;
  public readonly int JointCount;

  public static PipelineConfig DefaultConfig(PipelineKind kind) {
    PipelineConfig c;
    Check(Native.sb_pipeline_config_init(out c, kind), null);
    return c;
  }
  public Pipeline(Weights w, PipelineKind kind) : this(w, DefaultConfig(kind)) {}
  public Pipeline(Weights w, PipelineConfig cfg) {
    PipelineHandle h;
    Status s = Native.sb_pipeline_create(w.Handle, ref cfg, out h);
    if (s < 0) throw new SparsebodyException(s, Marshal.PtrToStringAnsi(Native.sb_last_error(IntPtr.Zero)));
    Handle = h;
    int n;
    Check(Native.sb_pipeline_joint_count(Handle, out n), Handle);
    JointCount = n;
  }
  internal Pipeline(PipelineHandle user) {  // a crowd's user
    Handle = user;
    int n;
    Check(Native.sb_pipeline_joint_count(Handle, out n), Handle);
    JointCount = n;
  }
  public void Dispose() { Handle.Dispose(); }

  internal static void Check(Status s, PipelineHandle h) {
    if (s >= 0) return;
    IntPtr m = h != null ? Native.sb_last_error(h) : Native.sb_last_error(IntPtr.Zero);
    throw new SparsebodyException(s, Marshal.PtrToStringAnsi(m));
  }

  // Returns the model steps run. A tracker flagged valid with NaN/Inf is used as lost (Status.NonfinitePose, no throw).
  public int Push(ref TrackerFrame f) {
    int steps;
    Check(Native.sb_pipeline_push(Handle, ref f, out steps), Handle);
    return steps;
  }
  // The pose into the caller's arrays (either may be null; length >= JointCount). False: no pose yet.
  public bool Read(Quatf[] localRotations, Vec3f[] worldPositions, out PoseInfo info) {
    info = new PoseInfo();
    info.structSize = (uint)Marshal.SizeOf(typeof(PoseInfo));
    int cap = Math.Min(localRotations != null ? localRotations.Length : int.MaxValue, worldPositions != null ? worldPositions.Length : int.MaxValue);
    if (cap == int.MaxValue) cap = 0;
    Status s = Native.sb_pipeline_read(Handle, ref info, localRotations, worldPositions, cap);
    Check(s, Handle);
    return s == Status.Ok;
  }
  public void Reset() { Check(Native.sb_pipeline_reset(Handle), Handle); }
  public string JointName(int j) {
    IntPtr n;
    Check(Native.sb_pipeline_joint_name(Handle, j, out n), Handle);
    return Marshal.PtrToStringAnsi(n);
  }
  public int[] JointParents() {
    var p = new int[JointCount];
    Check(Native.sb_pipeline_joint_parents(Handle, p, p.Length), Handle);
    return p;
  }
  public double FrameRate { get { double f; Check(Native.sb_pipeline_frame_rate(Handle, out f), Handle); return f; } }
  public void Recalibrate() { Check(Native.sb_pipeline_recalibrate(Handle), Handle); }
  // Recentred tracking spaces found so far, and the controllers found in the other hands (exchanged while ControllersSwapped).
  public int Recentres { get { int r, c, w; Check(Native.sb_pipeline_stream_events(Handle, out r, out c, out w), Handle); return r; } }
  public int ControllerSwaps { get { int r, c, w; Check(Native.sb_pipeline_stream_events(Handle, out r, out c, out w), Handle); return c; } }
  public bool ControllersSwapped { get { int r, c, w; Check(Native.sb_pipeline_stream_events(Handle, out r, out c, out w), Handle); return w != 0; } }
  // Stand-ups found so far (the user stood up from a seat: the model restarted there).
  public long StandUps { get { long n; Check(Native.sb_pipeline_stand_ups(Handle, out n), Handle); return n; } }
  public void CalibrateFrame(ref TrackerFrame f) { Check(Native.sb_pipeline_calibrate_frame(Handle, ref f), Handle); }
  public void SetJointCalibration(double scale) { Check(Native.sb_pipeline_set_joint_calibration(Handle, scale), Handle); }
  public CalibrationReport Calibration {
    get {
      var r = new CalibrationReport();
      r.structSize = (uint)Marshal.SizeOf(typeof(CalibrationReport));
      Check(Native.sb_pipeline_calibration(Handle, ref r), Handle);
      return r;
    }
  }
  public string LastError { get { return Marshal.PtrToStringAnsi(Native.sb_last_error(Handle)); } }
}

// Many avatars on one weight set (LoBSTr or N3PDirect, 1-64 users), stepped together: each model tick
// runs every user's network in one call (a social scene). Push takes one frame per user; Users[i]
// reads user i (Read, Calibration, Reset, ...) and is valid until the crowd is disposed. Each user
// gets exactly what a Pipeline of its own would give for the same frames.
public sealed class Crowd : IDisposable {
  public readonly CrowdHandle Handle;
  public readonly Pipeline[] Users;

  public Crowd(Weights w, PipelineKind kind, int users) : this(w, Pipeline.DefaultConfig(kind), users) {}
  public Crowd(Weights w, PipelineConfig cfg, int users) {
    CrowdHandle h;
    Status s = Native.sb_crowd_create(w.Handle, ref cfg, users, out h);
    if (s < 0) throw new SparsebodyException(s, Marshal.PtrToStringAnsi(Native.sb_last_error(IntPtr.Zero)));
    Handle = h;
    Users = new Pipeline[users];
    for (int i = 0; i < users; ++i) {
      IntPtr u;
      Check(Native.sb_crowd_user(Handle, i, out u));
      Users[i] = new Pipeline(new PipelineHandle(u));
    }
  }
  // frames[i]: user i's frame (frames.Length == Users.Length; a user with no new frame gets its last
  // one again). steps (may be null, else Users.Length long): the model steps each user ran.
  public void Push(TrackerFrame[] frames, int[] steps = null) {
    Check(Native.sb_crowd_push(Handle, frames, frames != null ? frames.Length : 0, steps));
  }
  public void Dispose() { Handle.Dispose(); }

  void Check(Status s) {
    if (s < 0) throw new SparsebodyException(s, Marshal.PtrToStringAnsi(Native.sb_last_error(Handle)));
  }
}

}  // namespace Sparsebody
