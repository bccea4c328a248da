package org.keygraph;

/**
 * A keygraph call failed: {@link #status()} is the C API's status code
 * (kg::StatusCode's stable numbers: 1 InvalidArgument, 2 NotFound, 3
 * IoError, 4 CorruptData, 5 UnsupportedVersion, 6 ResourceExhausted) and
 * the message is the library's one line.
 */
public class KeygraphException extends RuntimeException {
  private static final long serialVersionUID = 1L;
  private final int status;

  public KeygraphException(int status, String message) {
    super(message);
    this.status = status;
  }

  /** The status code (never 0). */
  public int status() {
    return status;
  }
}
