// The C# binding (examples/unity/Sparsebody.cs) on Mono: streams a tracker CSV session through the
// shared library and compares every frame's joint world positions with what the C++ pipelines gave
// for the same CSV (capi_reference: OUT_DIR/{lobstr,n3p_direct,n3p_physics}.ref). Also the binding's
// error paths: a missing file, a LoBSTr file as QuestSim, a wrong struct size, use after Dispose.
// Crowds (Sparsebody.Crowd): three users on the same session, shifted in frames and time, each equal
// to the C++ reference for its frames.
//   mono CSharpTest.exe SESSION.csv WEIGHTS_DIR REF_DIR     exit 0: all equal within kTolerance
using System;
using System.Collections.Generic;
using System.Globalization;
using System.IO;
using Sparsebody;

static class CSharpTest {
  // metres. Both sides run the same arithmetic (the reference is compiled with the library's ISA
  // flags), so the positions agree to the bit; the tolerance only allows for a CSV value parsed
  // to a different float by Mono than by strtod (1 ulp of a tracker coordinate).
  const double kTolerance = 1e-5;
  static int failures = 0;

  static void Expect(bool ok, string what) {
    if (!ok) { Console.Error.WriteLine("FAILED: " + what); ++failures; }
  }

  static List<TrackerFrame> ReadCsv(string path) {
    var frames = new List<TrackerFrame>();
    bool header = false;
    foreach (var line in File.ReadLines(path)) {
      if (line.Length == 0 || line[0] == '#') continue;
      if (!header) { header = true; continue; }
      var v = line.Split(',');
      if (v.Length != 33) throw new Exception(path + ": a row of " + v.Length + " fields");
      var f = TrackerFrame.Create();
      f.time = double.Parse(v[0], CultureInfo.InvariantCulture);
      var poses = new Posef[4];
      for (int k = 0; k < 4; ++k) {
        Func<int, float> F = i => (float)double.Parse(v[1 + 8 * k + i], CultureInfo.InvariantCulture);
        poses[k].position = new Vec3f { x = F(0), y = F(1), z = F(2) };
        poses[k].orientation = new Quatf { x = F(3), y = F(4), z = F(5), w = F(6) };
        if (v[8 + 8 * k] == "1") f.valid |= (TrackerValid)(1u << k);
      }
      f.head = poses[0]; f.leftHand = poses[1]; f.rightHand = poses[2]; f.pelvis = poses[3];
      frames.Add(f);
    }
    return frames;
  }

  static Dictionary<int, double[]> ReadRef(string path) {
    var r = new Dictionary<int, double[]>();
    foreach (var line in File.ReadLines(path)) {
      var v = line.Split(' ');
      var p = new double[v.Length - 1];
      for (int i = 1; i < v.Length; ++i) p[i - 1] = double.Parse(v[i], CultureInfo.InvariantCulture);
      r[int.Parse(v[0], CultureInfo.InvariantCulture)] = p;
    }
    return r;
  }

  static void Compare(string name, Weights w, PipelineKind kind, List<TrackerFrame> frames, string refPath) {
    var reference = ReadRef(refPath);
    using (var p = new Pipeline(w, kind)) {
      var rot = new Quatf[p.JointCount];
      var pos = new Vec3f[p.JointCount];
      int compared = 0, poses = 0;
      double maxDiff = 0;
      var sw = System.Diagnostics.Stopwatch.StartNew();
      for (int i = 0; i < frames.Count; ++i) {
        var f = frames[i];
        p.Push(ref f);
        PoseInfo info;
        if (!p.Read(rot, pos, out info)) {
          Expect(!reference.ContainsKey(i), name + ": frame " + i + " has a C++ pose but no C# pose");
          continue;
        }
        ++poses;
        double[] want;
        if (!reference.TryGetValue(i, out want)) { Expect(false, name + ": frame " + i + " has a C# pose but no C++ pose"); continue; }
        Expect(want.Length == 3 * p.JointCount, name + ": joint count");
        for (int j = 0; j < p.JointCount; ++j) {
          // the reference holds floats printed with 9 digits: parsed back to the same float
          maxDiff = Math.Max(maxDiff, Math.Abs(pos[j].x - (float)want[3 * j]));
          maxDiff = Math.Max(maxDiff, Math.Abs(pos[j].y - (float)want[3 * j + 1]));
          maxDiff = Math.Max(maxDiff, Math.Abs(pos[j].z - (float)want[3 * j + 2]));
        }
        ++compared;
      }
      sw.Stop();
      var cal = p.Calibration;
      Console.WriteLine("C# {0,-12} {1} frames pushed, {2} poses compared with C++ ({3} in the reference), max |diff| {4:G3} m (tolerance {5:G2} m); " +
                        "calibration {6}, stature {7:F2} m; {8:F1} us per frame (push + read, this run)",
                        name, frames.Count, compared, reference.Count, maxDiff, kTolerance, cal.state, cal.stature,
                        1e6 * sw.Elapsed.TotalSeconds / frames.Count);
      Expect(compared == reference.Count && compared > 100, name + ": compared " + compared + " of " + reference.Count);
      Expect(maxDiff <= kTolerance, name + ": max |diff| " + maxDiff + " m");
      Expect(cal.state == CalibrationState.Calibrated, name + ": the session's standing window was not found: " + cal.Message);
    }
  }

  // A crowd of 3 users on the session (user 1 one frame behind the others, user 2 on a clock 10 s
  // later): every user's positions equal the C++ reference for its own frame (as Compare's).
  static void CompareCrowd(string name, Weights w, PipelineKind kind, List<TrackerFrame> frames, string refPath) {
    var reference = ReadRef(refPath);
    using (var c = new Crowd(w, kind, 3)) {
      int n = c.Users[0].JointCount;
      var pos = new Vec3f[n];
      var input = new TrackerFrame[3];
      var steps = new int[3];
      int compared = 0;
      double maxDiff = 0;
      for (int i = 0; i <= frames.Count; ++i) {
        input[0] = frames[Math.Min(i, frames.Count - 1)];  // the last frame again at the end: no tick
        input[1] = frames[Math.Max(i - 1, 0)];
        input[2] = frames[Math.Min(i, frames.Count - 1)];
        input[2].time += 10.0;
        c.Push(input, steps);
        for (int u = 0; u < 3; ++u) {
          int at = u == 1 ? Math.Max(i - 1, 0) : Math.Min(i, frames.Count - 1);
          PoseInfo info;
          if (!c.Users[u].Read(null, pos, out info)) { Expect(!reference.ContainsKey(at), name + ": user " + u + " frame " + at + ": no pose"); continue; }
          double[] want;
          if (!reference.TryGetValue(at, out want)) continue;  // a repeated frame shows the last pose
          for (int j = 0; j < n; ++j) {
            maxDiff = Math.Max(maxDiff, Math.Abs(pos[j].x - (float)want[3 * j]));
            maxDiff = Math.Max(maxDiff, Math.Abs(pos[j].y - (float)want[3 * j + 1]));
            maxDiff = Math.Max(maxDiff, Math.Abs(pos[j].z - (float)want[3 * j + 2]));
          }
          ++compared;
        }
      }
      Console.WriteLine("C# crowd {0,-8} 3 users, {1} poses compared with C++, max |diff| {2:G3} m", name, compared, maxDiff);
      Expect(compared > 2 * reference.Count, name + " crowd: compared " + compared);
      Expect(maxDiff <= kTolerance, name + " crowd: max |diff| " + maxDiff + " m");
      Expect(steps[0] == 0, name + " crowd: a repeated frame ran " + steps[0] + " steps");
      try { c.Push(new TrackerFrame[2]); Expect(false, "2 frames for 3 users"); }
      catch (SparsebodyException e) { Expect(e.Status == Status.ErrInvalidArgument && e.Message.Contains("2 frames for a crowd of 3"), "crowd count: " + e.Message); }
    }
    try { new Crowd(w, PipelineKind.N3PPhysics, 2); Expect(false, "a physics crowd"); }
    catch (SparsebodyException e) { Expect(e.Status == Status.ErrInvalidArgument || e.Status == Status.ErrMismatch, "physics crowd: " + e.Message); }
  }

  // Weights in another storage: an int8 LoBSTr pipeline runs, and auto resolves to float or int8.
  static void Storages(string weightsDir, List<TrackerFrame> frames) {
    using (var w = Weights.Load(Model.LoBSTr, weightsDir + "/lobstr_compact.weights.json", Storage.Int8))
    using (var p = new Pipeline(w, PipelineKind.LoBSTr)) {
      Expect(w.Storage == Storage.Int8, "int8 storage: " + w.Storage);
      var pos = new Vec3f[p.JointCount];
      int poses = 0;
      foreach (var fr in frames) { var f = fr; p.Push(ref f); PoseInfo info; if (p.Read(null, pos, out info)) ++poses; }
      Expect(poses > 100, "int8 LoBSTr: " + poses + " poses");
    }
    using (var w = Weights.Load(Model.N3P, weightsDir + "/n3p", Storage.Auto))
      Expect(w.Storage == Storage.Int8 || w.Storage == Storage.Float, "auto storage: " + w.Storage);
    try { Weights.Load(Model.QuestSim, weightsDir + "/questsim_policy.json", Storage.F16); Expect(false, "f16 QuestSim loaded"); }
    catch (SparsebodyException e) { Expect(e.Status == Status.ErrUnsupported, "f16 QuestSim: " + e.Message); }
  }

  static void ErrorPaths(string weightsDir) {
    try { Weights.Load(Model.LoBSTr, "/nonexistent.json"); Expect(false, "missing file loaded"); }
    catch (SparsebodyException e) { Expect(e.Status == Status.ErrLoad && e.Message.Contains("/nonexistent.json"), "missing file: " + e.Message); }
    try { Weights.Load(Model.QuestSim, weightsDir + "/lobstr_compact.weights.json"); Expect(false, "LoBSTr file loaded as QuestSim"); }
    catch (SparsebodyException e) { Expect(e.Status == Status.ErrLoad && e.Message.Contains("lobstr_compact"), "QuestSim: " + e.Message); }
    using (var w = Weights.Load(Model.N3P, weightsDir + "/n3p")) {
      try { new Pipeline(w, PipelineKind.LoBSTr); Expect(false, "LoBSTr from N3P weights"); }
      catch (SparsebodyException e) { Expect(e.Status == Status.ErrMismatch, "mismatch: " + e.Message); }
      var p = new Pipeline(w, PipelineKind.N3PDirect);
      Expect(p.JointName(0).Length > 0 && p.JointParents()[0] == -1 && p.FrameRate == 30, "skeleton queries");
      Expect(p.Recentres == 0 && p.ControllerSwaps == 0 && !p.ControllersSwapped, "stream events before any input");
      Expect(p.StandUps == 0, "no stand-up before any input");
      var f = TrackerFrame.Create();
      f.structSize = 4;
      try { p.Push(ref f); Expect(false, "wrong struct size pushed"); }
      catch (SparsebodyException e) { Expect(e.Status == Status.ErrStructSize, "struct size: " + e.Message); }
      Quatf[] rot = new Quatf[p.JointCount];
      PoseInfo info;
      try { p.Read(rot, null, out info); Expect(false, "read before push"); }
      catch (SparsebodyException e) { Expect(e.Status == Status.ErrOrder, "order: " + e.Message); }
      try { p.Read(new Quatf[2], null, out info); Expect(false, "small array"); }
      catch (SparsebodyException e) { Expect(e.Status == Status.ErrCapacity, "capacity: " + e.Message); }
      p.Dispose();
      p.Dispose();  // twice: a no-op
      try { p.Reset(); Expect(false, "use after Dispose"); }
      catch (ObjectDisposedException) {}
    }
  }

  static int Main(string[] args) {
    if (args.Length != 3) { Console.Error.WriteLine("usage: CSharpTest.exe SESSION.csv WEIGHTS_DIR REF_DIR"); return 2; }
    Expect(Native.sb_api_version() == Native.ApiVersion, "API version");
    var frames = ReadCsv(args[0]);
    using (var lobstr = Weights.Load(Model.LoBSTr, args[1] + "/lobstr_compact.weights.json")) {
      Compare("lobstr", lobstr, PipelineKind.LoBSTr, frames, args[2] + "/lobstr.ref");
      CompareCrowd("lobstr", lobstr, PipelineKind.LoBSTr, frames, args[2] + "/lobstr.ref");
    }
    using (var n3p = Weights.Load(Model.N3P, args[1] + "/n3p")) {
      Compare("n3p_direct", n3p, PipelineKind.N3PDirect, frames, args[2] + "/n3p_direct.ref");
      CompareCrowd("n3p", n3p, PipelineKind.N3PDirect, frames, args[2] + "/n3p_direct.ref");
      Compare("n3p_physics", n3p, PipelineKind.N3PPhysics, frames, args[2] + "/n3p_physics.ref");
    }
    Storages(args[1], frames);
    ErrorPaths(args[1]);
    Console.WriteLine(failures == 0 ? "C# binding: all checks passed" : "C# binding: " + failures + " checks FAILED");
    return failures == 0 ? 0 : 1;
  }
}
