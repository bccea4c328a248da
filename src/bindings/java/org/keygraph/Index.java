package org.keygraph;

import java.nio.ByteBuffer;

/**
 * A model index (.kgi), opened and validated: a corrupt or hostile file is a
 * {@link KeygraphException}, never a crash. Read-only once open: one index
 * may serve detectors on several threads. Close it (try-with-resources)
 * after every {@link Detector} made from it; closing it while one is open
 * throws IllegalStateException.
 */
public final class Index implements AutoCloseable {
  private long handle;
  private final long copy;
  private final ByteBuffer keep; // the caller's bytes, used in place
  private final String[] names;
  private int openDetectors;

  private Index(long handle, long copy, ByteBuffer keep) {
    this.handle = handle;
    this.copy = copy;
    this.keep = keep;
    this.names = Native.indexModelNames(handle);
  }

  /** Maps and validates the file at {@code path} (kg_index_open). */
  public static Index open(String path) {
    if (path == null) throw new IllegalArgumentException("Index.open: path is null");
    return new Index(Native.indexOpen(path), 0, null);
  }

  /**
   * Validates the index bytes from the buffer's position to its limit. A
   * direct buffer whose bytes start at a 64-byte aligned address (e.g.
   * {@code ByteBuffer.allocateDirect(n + 64).alignedSlice(64)}, or a mapped
   * file) is used in place and must stay unchanged while the index is
   * open; any other buffer is copied once into memory the index owns.
   */
  public static Index fromBuffer(ByteBuffer buffer) {
    if (buffer == null) throw new IllegalArgumentException("Index.fromBuffer: buffer is null");
    final int size = buffer.remaining();
    long[] made;
    if (buffer.isDirect()) {
      made = Native.indexFromBuffer(buffer, null, buffer.position(), size);
    } else if (buffer.hasArray()) {
      made = Native.indexFromBuffer(null, buffer.array(), buffer.arrayOffset() + buffer.position(), size);
    } else {
      byte[] bytes = new byte[size];
      buffer.duplicate().get(bytes);
      made = Native.indexFromBuffer(null, bytes, 0, size);
    }
    return new Index(made[0], made[1], made[1] == 0 ? buffer : null);
  }

  public int modelCount() {
    return names.length;
  }

  /** Model {@code id}'s name. */
  public String modelName(int id) {
    if (id < 0 || id >= names.length) {
      throw new IllegalArgumentException("no model " + id + " in the index (" + names.length + " models)");
    }
    return names[id];
  }

  /** Whether the bytes given to {@link #fromBuffer} are used in place. */
  public boolean isInPlace() {
    return keep != null;
  }

  synchronized long handle() {
    if (handle == 0) throw new IllegalStateException("the index is closed");
    return handle;
  }

  synchronized void attach() {
    handle();
    ++openDetectors;
  }

  synchronized void detach() {
    --openDetectors;
  }

  @Override
  public synchronized void close() {
    if (handle == 0) return;
    if (openDetectors > 0) {
      throw new IllegalStateException("the index still has " + openDetectors + " open detector(s): close them first");
    }
    Native.indexDestroy(handle, copy);
    handle = 0;
  }

  /** The library version ("0.1.0"). */
  public static String version() {
    return Native.version();
  }
}
