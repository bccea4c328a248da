package org.keygraph.test;

import java.nio.ByteBuffer;
import java.nio.file.Files;
import java.nio.file.Path;
import java.util.Locale;
import org.keygraph.Detection;
import org.keygraph.Detector;
import org.keygraph.Index;

/**
 * The Java binding on real frames: finds an index's models in PGM frames and
 * prints what tests/capi/find.c prints (one line per detection), so that
 * compare_find.py holds it to the C++ API's corners. The index comes
 * through Index.fromBuffer (a direct, 64-byte aligned buffer: used in
 * place); each frame is a direct buffer whose rows are 40 bytes longer
 * than the image, as a camera's Y plane often is.
 *   java org.keygraph.test.FindScenes INDEX FRAME.pgm...
 */
public final class FindScenes {
  public static void main(String[] args) throws Exception {
    if (args.length < 2) {
      System.err.println("usage: FindScenes INDEX FRAME.pgm...");
      System.exit(2);
    }
    final byte[] file = Files.readAllBytes(Path.of(args[0]));
    final ByteBuffer aligned = ByteBuffer.allocateDirect(file.length + 64).alignedSlice(64);
    aligned.put(file, 0, file.length).flip();
    Pgm[] frames = new Pgm[args.length - 1];
    int maxWidth = 1;
    int maxHeight = 1;
    for (int i = 1; i < args.length; ++i) {
      frames[i - 1] = Pgm.read(Path.of(args[i]));
      maxWidth = Math.max(maxWidth, frames[i - 1].width);
      maxHeight = Math.max(maxHeight, frames[i - 1].height);
    }
    try (Index index = Index.fromBuffer(aligned); Detector detector = new Detector(index, maxWidth, maxHeight)) {
      if (!index.isInPlace()) throw new AssertionError("an aligned direct buffer was copied");
      for (int i = 0; i < frames.length; ++i) {
        final Pgm f = frames[i];
        final int stride = f.width + 40;
        ByteBuffer plane = ByteBuffer.allocateDirect(stride * f.height);
        for (int y = 0; y < f.height; ++y) {
          plane.position(y * stride);
          plane.put(f.pixels, y * f.width, f.width);
        }
        plane.position(0);
        final String name = Path.of(args[i + 1]).getFileName().toString();
        Detection[] found = detector.detect(plane, f.width, f.height, stride);
        if (found.length == 0) System.out.println(name + " none");
        for (Detection d : found) {
          StringBuilder line = new StringBuilder(name + " " + d.model);
          for (double c : d.corners) line.append(String.format(Locale.ROOT, " %.4f", c));
          line.append(String.format(Locale.ROOT, " inliers=%d confidence=%.4f", d.inliers, d.confidence));
          System.out.println(line);
        }
      }
    }
  }
}
