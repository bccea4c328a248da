package org.keygraph;

/**
 * One object found in a frame. Pixel (x, y) is column x, row y; the centre
 * of the top-left pixel is (0, 0). The homography is row-major and maps
 * model pixels to frame pixels.
 */
public final class Detection {
  static final int DOUBLES = 9 + 8 + 3; // homography, corners, score, appearance, confidence
  static final int INTS = 4;            // model id, inliers, track id, tracked

  /** The model's index in the index, and its name. */
  public final int modelId;
  public final String model;
  /** 3x3, row-major: model pixels to frame pixels. */
  public final double[] homography;
  /** The model's outline in the frame: x0, y0, .. x3, y3, clockwise from its top-left. */
  public final double[] corners;
  /** Distinct keypoint correspondences within the inlier threshold. */
  public final int inliers;
  /** Fraction of the model's keypoints confirmed in the frame. */
  public final double score;
  /** Appearance correlation in [0, 1]; -1 when not measured. */
  public final double appearance;
  /** Estimated probability, in [0, 1], that the detection is right. */
  public final double confidence;
  /** {@link Tracker} only: the object's id while it is followed (-1: not tracked). */
  public final int trackId;
  /** {@link Tracker} only: confirmed around its prediction (no detection ran). */
  public final boolean tracked;

  Detection(String[] names, double[] d, int[] n, int i) {
    final int o = i * DOUBLES;
    modelId = n[i * INTS];
    model = names[modelId];
    inliers = n[i * INTS + 1];
    trackId = n[i * INTS + 2];
    tracked = n[i * INTS + 3] != 0;
    homography = java.util.Arrays.copyOfRange(d, o, o + 9);
    corners = java.util.Arrays.copyOfRange(d, o + 9, o + 17);
    score = d[o + 17];
    appearance = d[o + 18];
    confidence = d[o + 19];
  }
}
