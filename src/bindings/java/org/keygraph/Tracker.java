package org.keygraph;

import java.nio.ByteBuffer;

/**
 * Follows what a {@link Detector} finds from frame to frame (live video):
 * each object's corners are predicted and confirmed by aligning the model's
 * stored appearance, full detection runs when nothing is followed, when an
 * object is lost and every detectInterval frames, and an object keeps its
 * {@link Detection#trackId} while it is followed. Frames in order; its
 * methods hold the detector's lock, so the detector serves no one else
 * meanwhile. Close it before its detector.
 */
public final class Tracker implements AutoCloseable {
  private final Detector detector;
  private long handle;

  /** Detection every 10 frames, tracks kept while they correlate 0.75, up to 16, no smoothing. */
  public Tracker(Detector detector) {
    this(detector, 10, 0.75, 16, 0.0);
  }

  public Tracker(Detector detector, int detectInterval, double minCorrelation, int maxTracks, double smoothing) {
    if (detector == null) throw new IllegalArgumentException("Tracker: detector is null");
    this.detector = detector;
    synchronized (detector) {
      final long d = detector.attach();
      try {
        handle = Native.trackerCreate(d, detectInterval, minCorrelation, maxTracks, smoothing);
      } catch (RuntimeException e) {
        detector.detach();
        throw e;
      }
    }
  }

  /** False for an index without model appearances: every frame is then detected. */
  public synchronized boolean canTrack() {
    return Native.trackerCanTrack(live());
  }

  /** The objects in the grey plane (as {@link Detector#detect(ByteBuffer, int, int, int)} takes it). */
  public synchronized Detection[] process(ByteBuffer yPlane, int width, int height, int rowStride) {
    if (yPlane == null) throw new IllegalArgumentException("process: yPlane is null");
    if (!yPlane.isDirect() && !yPlane.hasArray()) {
      throw new IllegalArgumentException("process: a read-only heap buffer; pass a direct buffer");
    }
    Detector.checkLayout(yPlane.remaining(), width, height, rowStride);
    synchronized (detector) {
      final double[] doubles = new double[64 * Detection.DOUBLES];
      final int[] ints = new int[64 * Detection.INTS];
      final int count = yPlane.isDirect()
          ? Native.trackerProcess(live(), yPlane, null, yPlane.position(), width, height, rowStride, doubles, ints)
          : Native.trackerProcess(live(), null, yPlane.array(), yPlane.arrayOffset() + yPlane.position(), width,
              height, rowStride, doubles, ints);
      Detection[] out = new Detection[count];
      for (int i = 0; i < count; ++i) out[i] = new Detection(detector.names(), doubles, ints, i);
      return out;
    }
  }

  /** Forgets every track (a new scene, a camera switch). */
  public synchronized void reset() {
    Native.trackerReset(live());
  }

  @Override
  public synchronized void close() {
    if (handle == 0) return;
    Native.trackerDestroy(handle);
    handle = 0;
    detector.detach();
  }

  private long live() {
    if (handle == 0) throw new IllegalStateException("the tracker is closed");
    return handle;
  }
}
