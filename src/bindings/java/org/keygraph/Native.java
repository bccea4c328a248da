package org.keygraph;

/**
 * The JNI glue (libkeygraph_jni, src/bindings/java/keygraph_jni.cpp) over
 * the C API. Handles are the C API's pointers as longs; every method checks
 * its arguments and throws {@link KeygraphException} or
 * IllegalArgumentException rather than crash.
 */
final class Native {
  static {
    System.loadLibrary("keygraph_jni");
  }

  private Native() {}

  static native String version();

  /** Opens (maps) the file; returns the kg_index handle. */
  static native long indexOpen(String path);

  /**
   * Uses {@code size} bytes at {@code offset} of a direct buffer in place
   * when they are 64-byte aligned; otherwise copies them once into aligned
   * memory the index owns. Returns {handle, copy} (copy 0 when in place).
   */
  static native long[] indexFromBuffer(java.nio.ByteBuffer buffer, byte[] array, int offset, int size);

  static native void indexDestroy(long handle, long copy);

  static native String[] indexModelNames(long handle);

  /** limits: max width, max height, threads (0: the default). */
  static native long detectorCreate(long index, int maxWidth, int maxHeight, int threads);

  static native void detectorDestroy(long handle);

  static native void detectorSetOption(long handle, String name, String value);

  static native void detectorSetModels(long handle, int[] ids);

  /**
   * Detects in the plane (a direct buffer, or {@code array} when buffer is
   * null) whose first pixel is at {@code offset}; fills per detection
   * {@link Detection#DOUBLES} doubles and {@link Detection#INTS} ints and
   * returns the count.
   */
  static native int detect(long handle, java.nio.ByteBuffer buffer, byte[] array, int offset, int width,
      int height, int rowStride, double[] doubles, int[] ints);

  static native long trackerCreate(long detector, int detectInterval, double minCorrelation, int maxTracks,
      double smoothing);

  static native void trackerDestroy(long handle);

  static native boolean trackerCanTrack(long handle);

  static native void trackerReset(long handle);

  /** As {@link #detect}, through the tracker. */
  static native int trackerProcess(long handle, java.nio.ByteBuffer buffer, byte[] array, int offset, int width,
      int height, int rowStride, double[] doubles, int[] ints);
}
