package org.keygraph.test;

import java.io.IOException;
import java.nio.file.Files;
import java.nio.file.Path;

/** A binary PGM (P5, maxval 255) as the Java tests read their frames. */
final class Pgm {
  final int width;
  final int height;
  final byte[] pixels; // rows packed

  private Pgm(int width, int height, byte[] pixels) {
    this.width = width;
    this.height = height;
    this.pixels = pixels;
  }

  static Pgm read(Path path) throws IOException {
    final byte[] bytes = Files.readAllBytes(path);
    int[] at = {2};
    if (bytes.length < 2 || bytes[0] != 'P' || bytes[1] != '5') throw new IOException(path + ": not a P5 PGM");
    final int width = number(bytes, at);
    final int height = number(bytes, at);
    final int maxval = number(bytes, at);
    final int start = at[0] + 1; // one whitespace byte after maxval
    if (maxval != 255 || width <= 0 || height <= 0 || start + (long) width * height > bytes.length) {
      throw new IOException(path + ": unsupported or truncated PGM");
    }
    byte[] pixels = new byte[width * height];
    System.arraycopy(bytes, start, pixels, 0, pixels.length);
    return new Pgm(width, height, pixels);
  }

  private static int number(byte[] b, int[] at) throws IOException {
    int i = at[0];
    while (i < b.length && (Character.isWhitespace(b[i]) || b[i] == '#')) {
      if (b[i] == '#') {
        while (i < b.length && b[i] != '\n') ++i;
      } else {
        ++i;
      }
    }
    int value = 0;
    int digits = 0;
    while (i < b.length && b[i] >= '0' && b[i] <= '9' && value < 1000000) {
      value = value * 10 + (b[i++] - '0');
      ++digits;
    }
    if (digits == 0) throw new IOException("bad PGM header");
    at[0] = i;
    return value;
  }
}
