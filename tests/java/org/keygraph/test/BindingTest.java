package org.keygraph.test;

import java.nio.ByteBuffer;
import java.nio.file.Files;
import java.nio.file.Path;
import java.util.Arrays;
import org.keygraph.Detection;
import org.keygraph.Detector;
import org.keygraph.Index;
import org.keygraph.KeygraphException;
import org.keygraph.Tracker;

/**
 * The Java binding's contract: bad input (null arguments, bad layouts,
 * planes too small, frames larger than the limits, bad options and model
 * ids, missing, truncated and corrupt indexes, closed handles) is an
 * exception with a message, never a crash; the plane's three forms (direct
 * buffer, heap buffer, byte array with an offset) find the same corners;
 * the model selection holds across options.
 *   java org.keygraph.test.BindingTest INDEX box_in_scene.pgm
 * INDEX holds "box" (found in box_in_scene) and a second model.
 */
public final class BindingTest {
  private static int passed;
  private static int failed;

  interface Call {
    void run() throws Exception;
  }

  private static void check(boolean ok, String what) {
    if (ok) {
      ++passed;
    } else {
      ++failed;
      System.err.println("FAILED: " + what);
    }
  }

  /** `call` throws `type` (and, for KeygraphException, `status`) with a message containing `part`. */
  private static void throwsWith(Class<?> type, int status, String part, String what, Call call) {
    try {
      call.run();
      check(false, what + ": no exception");
    } catch (Exception e) {
      boolean ok = type.isInstance(e) && e.getMessage() != null && e.getMessage().contains(part);
      if (ok && e instanceof KeygraphException) ok = ((KeygraphException) e).status() == status;
      check(ok, what + ": " + e);
    }
  }

  private static ByteBuffer alignedCopy(byte[] bytes, int misalign) {
    ByteBuffer b = ByteBuffer.allocateDirect(bytes.length + 128).alignedSlice(64);
    b.position(misalign);
    b = b.slice();
    b.put(bytes).flip();
    return b;
  }

  public static void main(String[] args) throws Exception {
    if (args.length != 2) {
      System.err.println("usage: BindingTest INDEX box_in_scene.pgm");
      System.exit(2);
    }
    final byte[] file = Files.readAllBytes(Path.of(args[0]));
    final Pgm scene = Pgm.read(Path.of(args[1]));
    final int w = scene.width;
    final int h = scene.height;

    check(Index.version().matches("\\d+\\.\\d+\\.\\d+"), "version " + Index.version());
    throwsWith(IllegalArgumentException.class, 0, "null", "open(null)", () -> Index.open(null));
    throwsWith(KeygraphException.class, 2, "nowhere.kgi", "missing file", () -> Index.open("/nonexistent/nowhere.kgi"));
    throwsWith(IllegalArgumentException.class, 0, "null", "fromBuffer(null)", () -> Index.fromBuffer(null));
    throwsWith(KeygraphException.class, 4, "", "truncated index",
        () -> Index.fromBuffer(alignedCopy(Arrays.copyOf(file, file.length / 2), 0)));
    byte[] flipped = file.clone();
    flipped[flipped.length / 3] ^= 0x10;
    throwsWith(KeygraphException.class, 4, "", "bit-flipped index", () -> Index.fromBuffer(ByteBuffer.wrap(flipped)));
    throwsWith(KeygraphException.class, 4, "", "empty index", () -> Index.fromBuffer(ByteBuffer.allocate(0)));

    try (Index heap = Index.fromBuffer(ByteBuffer.wrap(file));
         Index misaligned = Index.fromBuffer(alignedCopy(file, 1));
         Index inPlace = Index.fromBuffer(alignedCopy(file, 0));
         Index index = Index.open(args[0])) {
      check(!heap.isInPlace() && !misaligned.isInPlace() && inPlace.isInPlace(), "in place only when direct and aligned");
      check(index.modelCount() >= 2 && index.modelName(0).equals("box"), "models " + index.modelCount());
      throwsWith(IllegalArgumentException.class, 0, "no model", "modelName(-1)", () -> index.modelName(-1));

      throwsWith(IllegalArgumentException.class, 0, "null", "Detector(null)", () -> new Detector(null));
      throwsWith(KeygraphException.class, 1, "limits", "zero width limit", () -> new Detector(index, 0, 480));
      throwsWith(KeygraphException.class, 1, "threads", "65 threads", () -> new Detector(index, 640, 480, 65));

      try (Detector detector = new Detector(index, w, h)) {
        final ByteBuffer direct = ByteBuffer.allocateDirect(scene.pixels.length);
        direct.put(scene.pixels).flip();
        throwsWith(IllegalArgumentException.class, 0, "null", "detect(null)", () -> detector.detect((ByteBuffer) null, w, h, w));
        throwsWith(IllegalArgumentException.class, 0, "width and height", "zero width", () -> detector.detect(direct, 0, h, w));
        throwsWith(IllegalArgumentException.class, 0, "below the width", "stride < width", () -> detector.detect(direct, w, h, w - 1));
        throwsWith(IllegalArgumentException.class, 0, "needs", "plane too small", () -> detector.detect(direct, w, h, w + 1));
        throwsWith(IllegalArgumentException.class, 0, "offset", "offset past the array",
            () -> detector.detect(scene.pixels, scene.pixels.length + 1, w, h, w));
        final ByteBuffer large = ByteBuffer.allocateDirect((w + 1) * h);
        throwsWith(KeygraphException.class, 1, "larger than the detector's limits", "frame over the limits",
            () -> detector.detect(large, w + 1, h, w + 1));
        throwsWith(IllegalArgumentException.class, 0, "read-only", "read-only heap buffer",
            () -> detector.detect(ByteBuffer.wrap(scene.pixels).asReadOnlyBuffer(), w, h, w));
        throwsWith(KeygraphException.class, 1, "no.such", "unknown option", () -> detector.setOption("no.such", "1"));
        throwsWith(KeygraphException.class, 1, "fixed by the index", "index parameter",
            () -> detector.setOption("graph.structure", "4"));
        throwsWith(KeygraphException.class, 1, "min_confidence", "out of range", () -> detector.setOption("min_confidence", "3"));
        throwsWith(IllegalArgumentException.class, 0, "null", "null option", () -> detector.setOption(null, "1"));
        throwsWith(KeygraphException.class, 1, "not in the index", "model 99", () -> detector.setModels(99));
        throwsWith(IllegalStateException.class, 0, "open detector", "index closed under a detector", index::close);

        // The same corners from a direct buffer, a heap buffer and an array at an offset.
        Detection[] a = detector.detect(direct, w, h, w);
        Detection[] b = detector.detect(ByteBuffer.wrap(scene.pixels), w, h, w);
        byte[] shifted = new byte[scene.pixels.length + 7];
        System.arraycopy(scene.pixels, 0, shifted, 7, scene.pixels.length);
        Detection[] c = detector.detect(shifted, 7, w, h, w);
        check(a.length == 1 && a[0].model.equals("box"), "box found: " + a.length);
        check(a.length == b.length && b.length == c.length && a.length > 0
            && Arrays.equals(a[0].corners, b[0].corners) && Arrays.equals(a[0].corners, c[0].corners),
            "same corners from every plane form");
        // Looking for the other model only: an option set by name keeps that selection.
        detector.setModels(1);
        detector.setOption("ransac.seed", "7");
        check(detector.detect(direct, w, h, w).length == 0, "model selection survives setOption");
        detector.setModels();
        check(detector.detect(direct, w, h, w).length == 1, "every model again");

        // The tracker on windows of the scene moving 4 px right, 2 px down a frame.
        throwsWith(IllegalArgumentException.class, 0, "null", "Tracker(null)", () -> new Tracker(null));
        throwsWith(KeygraphException.class, 1, "detect_interval", "bad tracker option",
            () -> new Tracker(detector, 0, 0.75, 16, 0.0));
        try (Tracker tracker = new Tracker(detector)) {
          check(tracker.canTrack(), "the scenes' index can be tracked");
          throwsWith(IllegalStateException.class, 0, "open tracker", "detector closed under a tracker", detector::close);
          int id = -1;
          int tracked = 0;
          boolean sameId = true;
          for (int k = 0; k < 12; ++k) {
            ByteBuffer window = direct.duplicate();
            window.position(2 * k * w + 4 * k);
            Detection[] t = tracker.process(window, w - 48, h - 24, w);
            if (t.length != 1) {
              check(false, "frame " + k + ": " + t.length + " objects");
              continue;
            }
            if (k == 0) id = t[0].trackId;
            sameId &= t[0].trackId == id && id >= 0;
            tracked += t[0].tracked ? 1 : 0;
          }
          check(sameId, "one track id over the sequence");
          check(tracked >= 10, "tracked on " + tracked + " of 12 frames");
          throwsWith(KeygraphException.class, 1, "larger than", "frame over the tracker's limits",
              () -> tracker.process(large, w + 1, h, w + 1));
        }
        detector.close();
        throwsWith(IllegalStateException.class, 0, "closed", "detect after close", () -> detector.detect(direct, w, h, w));
      }
    }
    System.out.println(passed + " passed, " + failed + " failed");
    System.exit(failed == 0 ? 0 : 1);
  }
}
