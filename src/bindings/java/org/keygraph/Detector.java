package org.keygraph;

import java.nio.ByteBuffer;

/**
 * Detects an index's models in 8-bit grey frames (the Y plane of an
 * NV12/NV21/YUV420 camera frame is one). The workspace is allocated once,
 * here, for frames up to maxWidth x maxHeight; a larger frame is an error.
 * Not thread-safe by itself: its methods are synchronized, so use one per
 * thread for parallel work. Close it (try-with-resources) before its index.
 */
public final class Detector implements AutoCloseable {
  private final Index index;
  private final String[] names;
  private long handle;
  private int openTrackers;
  private final double[] doubles = new double[64 * Detection.DOUBLES];
  private final int[] ints = new int[64 * Detection.INTS];

  /** For frames up to 640 x 480, on the calling thread. */
  public Detector(Index index) {
    this(index, 640, 480, 1);
  }

  /** For frames up to maxWidth x maxHeight. */
  public Detector(Index index, int maxWidth, int maxHeight) {
    this(index, maxWidth, maxHeight, 1);
  }

  /** The same, with {@code threads} threads per frame (1..64). */
  public Detector(Index index, int maxWidth, int maxHeight, int threads) {
    if (index == null) throw new IllegalArgumentException("Detector: index is null");
    this.index = index;
    index.attach();
    try {
      handle = Native.detectorCreate(index.handle(), maxWidth, maxHeight, threads);
    } catch (RuntimeException e) {
      index.detach();
      throw e;
    }
    names = new String[index.modelCount()];
    for (int i = 0; i < names.length; ++i) names[i] = index.modelName(i);
  }

  /**
   * Sets a runtime option by name, as {@code keygraph detect --set} does
   * ("ransac.seed", "min_confidence", "descriptor.max_search_leaves", ...).
   */
  public synchronized void setOption(String name, String value) {
    if (name == null || value == null) throw new IllegalArgumentException("setOption: null name or value");
    Native.detectorSetOption(live(), name, value);
  }

  /** The models to look for (no ids: every model). */
  public synchronized void setModels(int... ids) {
    Native.detectorSetModels(live(), ids == null ? new int[0] : ids);
  }

  /**
   * Detects in the grey plane from the buffer's position: row y starts
   * {@code y * rowStride} bytes in. A direct buffer is read in place; a
   * heap buffer through its array. Returns the detections (none: an empty
   * array).
   */
  public synchronized Detection[] detect(ByteBuffer yPlane, int width, int height, int rowStride) {
    if (yPlane == null) throw new IllegalArgumentException("detect: yPlane is null");
    checkLayout(yPlane.remaining(), width, height, rowStride);
    int count;
    if (yPlane.isDirect()) {
      count = Native.detect(live(), yPlane, null, yPlane.position(), width, height, rowStride, doubles, ints);
    } else if (yPlane.hasArray()) {
      count = Native.detect(live(), null, yPlane.array(), yPlane.arrayOffset() + yPlane.position(), width, height,
          rowStride, doubles, ints);
    } else {
      throw new IllegalArgumentException("detect: a read-only heap buffer; pass a direct buffer or a byte[]");
    }
    return results(count);
  }

  /** The same on a byte array, from {@code offset}. */
  public synchronized Detection[] detect(byte[] yPlane, int offset, int width, int height, int rowStride) {
    if (yPlane == null) throw new IllegalArgumentException("detect: yPlane is null");
    if (offset < 0 || offset > yPlane.length) throw new IllegalArgumentException("detect: offset out of the array");
    checkLayout(yPlane.length - offset, width, height, rowStride);
    return results(Native.detect(live(), null, yPlane, offset, width, height, rowStride, doubles, ints));
  }

  @Override
  public synchronized void close() {
    if (handle == 0) return;
    if (openTrackers > 0) {
      throw new IllegalStateException("the detector still has " + openTrackers + " open tracker(s): close them first");
    }
    Native.detectorDestroy(handle);
    handle = 0;
    index.detach();
  }

  long live() {
    if (handle == 0) throw new IllegalStateException("the detector is closed");
    return handle;
  }

  synchronized long attach() {
    final long h = live();
    ++openTrackers;
    return h;
  }

  synchronized void detach() {
    --openTrackers;
  }

  // The plane must hold every row it claims: (height - 1) * rowStride + width bytes.
  static void checkLayout(long available, int width, int height, int rowStride) {
    if (width <= 0 || height <= 0) {
      throw new IllegalArgumentException("detect: width and height must be > 0 (got " + width + "x" + height + ")");
    }
    if (rowStride < width) {
      throw new IllegalArgumentException("detect: rowStride " + rowStride + " is below the width " + width);
    }
    final long needed = (long) (height - 1) * rowStride + width;
    if (needed > available) {
      throw new IllegalArgumentException("detect: the plane holds " + available + " bytes, a " + width + "x" + height
          + " frame with row stride " + rowStride + " needs " + needed);
    }
  }

  String[] names() {
    return names;
  }

  Detection[] results(int count) {
    Detection[] out = new Detection[count];
    for (int i = 0; i < count; ++i) out[i] = new Detection(names, doubles, ints, i);
    return out;
  }
}
