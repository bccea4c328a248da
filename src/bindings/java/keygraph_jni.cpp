// JNI glue of org.keygraph.Native over the C API (keygraph/keygraph.h):
// arguments checked here, C API errors thrown as KeygraphException(status,
// message), layout errors as IllegalArgumentException; never a crash. It
// includes only <jni.h> and the C API, so the Android NDK builds it as it
// is (README, "Android").
#include <jni.h>

#include <cstdint>
#include <cstdlib>
#include <cstring>

#include "keygraph/keygraph.h"

namespace {

void throw_illegal(JNIEnv* env, const char* message) {
  if (jclass c = env->FindClass("java/lang/IllegalArgumentException")) env->ThrowNew(c, message);
}

// Throws KeygraphException for `status` with this thread's last C API error.
void throw_status(JNIEnv* env, kg_status status) {
  jclass c = env->FindClass("org/keygraph/KeygraphException");
  if (c == nullptr) return;  // NoClassDefFoundError pending
  jmethodID init = env->GetMethodID(c, "<init>", "(ILjava/lang/String;)V");
  jstring message = env->NewStringUTF(kg_last_error());
  if (init == nullptr || message == nullptr) return;
  if (jobject e = env->NewObject(c, init, static_cast<jint>(status), message))
    env->Throw(static_cast<jthrowable>(e));
}

kg_index* as_index(jlong h) {
  return reinterpret_cast<kg_index*>(static_cast<std::intptr_t>(h));
}
kg_detector* as_detector(jlong h) {
  return reinterpret_cast<kg_detector*>(static_cast<std::intptr_t>(h));
}
kg_tracker* as_tracker(jlong h) {
  return reinterpret_cast<kg_tracker*>(static_cast<std::intptr_t>(h));
}
jlong as_handle(const void* p) {
  return static_cast<jlong>(reinterpret_cast<std::intptr_t>(p));
}

// Bytes [offset, offset + size) of a direct buffer or an array: the direct
// buffer's address, or the array's elements pinned (release_bytes()).
struct Bytes {
  std::uint8_t* data = nullptr;
  jbyteArray array = nullptr;
  jbyte* elements = nullptr;
};

bool get_bytes(JNIEnv* env, jobject buffer, jbyteArray array, jint offset, jlong size, Bytes& out) {
  if (offset < 0 || size < 0) {
    throw_illegal(env, "negative offset or size");
    return false;
  }
  if (buffer != nullptr) {
    auto* base = static_cast<std::uint8_t*>(env->GetDirectBufferAddress(buffer));
    const jlong capacity = env->GetDirectBufferCapacity(buffer);
    if (base == nullptr || capacity < 0) {
      throw_illegal(env, "not a direct buffer");
      return false;
    }
    if (offset + size > capacity) {
      throw_illegal(env, "the bytes run past the buffer's end");
      return false;
    }
    out.data = base + offset;
    return true;
  }
  if (array == nullptr) {
    throw_illegal(env, "no buffer and no array");
    return false;
  }
  if (offset + size > env->GetArrayLength(array)) {
    throw_illegal(env, "the bytes run past the array's end");
    return false;
  }
  out.elements = env->GetByteArrayElements(array, nullptr);
  if (out.elements == nullptr) return false;  // OutOfMemoryError pending
  out.array = array;
  out.data = reinterpret_cast<std::uint8_t*>(out.elements) + offset;
  return true;
}

void release_bytes(JNIEnv* env, Bytes& bytes) {
  if (bytes.elements != nullptr)
    env->ReleaseByteArrayElements(bytes.array, bytes.elements, JNI_ABORT);
  bytes.elements = nullptr;
}

// A frame through `call` (kg_detect or kg_tracker_process on a handle):
// the plane checked and wrapped, the results written per detection as
// Detection.DOUBLES doubles and Detection.INTS ints; their count.
template <class Call>
jint run_frame(JNIEnv* env, Call call, jobject buffer, jbyteArray array, jint offset, jint width,
               jint height, jint row_stride, jdoubleArray doubles, jintArray ints) {
  if (width <= 0 || height <= 0 || row_stride < width) {
    throw_illegal(env, "bad frame layout (width and height > 0, row stride >= width)");
    return 0;
  }
  constexpr int kDoubles = 20, kInts = 4;  // Detection.DOUBLES, Detection.INTS
  if (doubles == nullptr || ints == nullptr ||
      env->GetArrayLength(doubles) < KG_MAX_DETECTIONS * kDoubles ||
      env->GetArrayLength(ints) < KG_MAX_DETECTIONS * kInts) {
    throw_illegal(env, "result arrays too small");
    return 0;
  }
  Bytes bytes;
  const jlong size = static_cast<jlong>(height - 1) * row_stride + width;
  if (!get_bytes(env, buffer, array, offset, size, bytes)) return 0;
  const kg_image image{bytes.data, width, height, static_cast<std::ptrdiff_t>(row_stride)};
  kg_detection found[KG_MAX_DETECTIONS];
  std::size_t count = 0;
  const kg_status s = call(&image, found, &count);
  release_bytes(env, bytes);
  if (s != KG_OK) {
    throw_status(env, s);
    return 0;
  }
  for (std::size_t i = 0; i < count; ++i) {
    const kg_detection& d = found[i];
    jdouble row[kDoubles];
    for (int k = 0; k < 9; ++k) row[k] = d.homography[k];
    for (int c = 0; c < 4; ++c) {
      row[9 + 2 * c] = d.corners[c][0];
      row[10 + 2 * c] = d.corners[c][1];
    }
    row[17] = d.score;
    row[18] = d.appearance;
    row[19] = d.confidence;
    const jint numbers[kInts] = {d.model_id, d.inliers, d.track_id, d.tracked};
    env->SetDoubleArrayRegion(doubles, static_cast<jsize>(i) * kDoubles, kDoubles, row);
    env->SetIntArrayRegion(ints, static_cast<jsize>(i) * kInts, kInts, numbers);
  }
  return static_cast<jint>(count);
}

}  // namespace

extern "C" {

JNIEXPORT jstring JNICALL Java_org_keygraph_Native_version(JNIEnv* env, jclass) {
  return env->NewStringUTF(kg_version());
}

JNIEXPORT jlong JNICALL Java_org_keygraph_Native_indexOpen(JNIEnv* env, jclass, jstring path) {
  if (path == nullptr) {
    throw_illegal(env, "path is null");
    return 0;
  }
  const char* chars = env->GetStringUTFChars(path, nullptr);
  if (chars == nullptr) return 0;
  kg_index* index = nullptr;
  const kg_status s = kg_index_open(chars, &index);
  env->ReleaseStringUTFChars(path, chars);
  if (s != KG_OK) throw_status(env, s);
  return as_handle(index);
}

JNIEXPORT jlongArray JNICALL Java_org_keygraph_Native_indexFromBuffer(JNIEnv* env, jclass,
                                                                      jobject buffer,
                                                                      jbyteArray array, jint offset,
                                                                      jint size) {
  Bytes bytes;
  if (!get_bytes(env, buffer, array, offset, size, bytes)) return nullptr;
  // In place when direct and aligned; otherwise one aligned copy the index owns.
  void* copy = nullptr;
  const void* data = bytes.data;
  if (buffer == nullptr || reinterpret_cast<std::uintptr_t>(bytes.data) % 64 != 0) {
    if (::posix_memalign(&copy, 64, size == 0 ? 1 : static_cast<std::size_t>(size)) != 0) {
      release_bytes(env, bytes);
      throw_illegal(env, "out of memory for a copy of the index");
      return nullptr;
    }
    std::memcpy(copy, bytes.data, static_cast<std::size_t>(size));
    data = copy;
  }
  release_bytes(env, bytes);
  kg_index* index = nullptr;
  const kg_status s = kg_index_from_memory(data, static_cast<std::size_t>(size), &index);
  if (s != KG_OK) {
    std::free(copy);
    throw_status(env, s);
    return nullptr;
  }
  jlongArray out = env->NewLongArray(2);
  if (out == nullptr) {
    kg_index_destroy(index);
    std::free(copy);
    return nullptr;
  }
  const jlong made[2] = {as_handle(index), as_handle(copy)};
  env->SetLongArrayRegion(out, 0, 2, made);
  return out;
}

JNIEXPORT void JNICALL Java_org_keygraph_Native_indexDestroy(JNIEnv*, jclass, jlong handle,
                                                             jlong copy) {
  kg_index_destroy(as_index(handle));
  std::free(reinterpret_cast<void*>(static_cast<std::intptr_t>(copy)));
}

JNIEXPORT jobjectArray JNICALL Java_org_keygraph_Native_indexModelNames(JNIEnv* env, jclass,
                                                                        jlong handle) {
  const kg_index* index = as_index(handle);
  const int count = kg_index_model_count(index);
  jclass string_class = env->FindClass("java/lang/String");
  if (string_class == nullptr) return nullptr;
  jobjectArray names = env->NewObjectArray(count, string_class, nullptr);
  for (int i = 0; names != nullptr && i < count; ++i) {
    jstring name = env->NewStringUTF(kg_index_model_name(index, i));
    if (name == nullptr) return nullptr;
    env->SetObjectArrayElement(names, i, name);
    env->DeleteLocalRef(name);
  }
  return names;
}

JNIEXPORT jlong JNICALL Java_org_keygraph_Native_detectorCreate(JNIEnv* env, jclass, jlong index,
                                                                jint max_width, jint max_height,
                                                                jint threads) {
  kg_limits limits;
  kg_limits_default(&limits);
  limits.max_width = max_width;
  limits.max_height = max_height;
  limits.threads = threads;
  kg_detector* detector = nullptr;
  if (const kg_status s = kg_detector_create(as_index(index), &limits, &detector); s != KG_OK)
    throw_status(env, s);
  return as_handle(detector);
}

JNIEXPORT void JNICALL Java_org_keygraph_Native_detectorDestroy(JNIEnv*, jclass, jlong handle) {
  kg_detector_destroy(as_detector(handle));
}

JNIEXPORT void JNICALL Java_org_keygraph_Native_detectorSetOption(JNIEnv* env, jclass, jlong handle,
                                                                  jstring name, jstring value) {
  if (name == nullptr || value == nullptr) {
    throw_illegal(env, "null option name or value");
    return;
  }
  const char* n = env->GetStringUTFChars(name, nullptr);
  const char* v = n == nullptr ? nullptr : env->GetStringUTFChars(value, nullptr);
  kg_status s = KG_OK;
  if (n != nullptr && v != nullptr) s = kg_detector_set_option(as_detector(handle), n, v);
  if (v != nullptr) env->ReleaseStringUTFChars(value, v);
  if (n != nullptr) env->ReleaseStringUTFChars(name, n);
  if (s != KG_OK) throw_status(env, s);
}

JNIEXPORT void JNICALL Java_org_keygraph_Native_detectorSetModels(JNIEnv* env, jclass, jlong handle,
                                                                  jintArray ids) {
  const jsize count = ids == nullptr ? 0 : env->GetArrayLength(ids);
  jint* elements = count == 0 ? nullptr : env->GetIntArrayElements(ids, nullptr);
  if (count > 0 && elements == nullptr) return;
  static_assert(sizeof(jint) == sizeof(std::int32_t), "jint is 32 bits");
  const kg_status s =
      kg_detector_set_models(as_detector(handle), reinterpret_cast<const std::int32_t*>(elements),
                             static_cast<std::size_t>(count));
  if (elements != nullptr) env->ReleaseIntArrayElements(ids, elements, JNI_ABORT);
  if (s != KG_OK) throw_status(env, s);
}

JNIEXPORT jint JNICALL Java_org_keygraph_Native_detect(JNIEnv* env, jclass, jlong handle,
                                                       jobject buffer, jbyteArray array,
                                                       jint offset, jint width, jint height,
                                                       jint row_stride, jdoubleArray doubles,
                                                       jintArray ints) {
  return run_frame(
      env,
      [handle](const kg_image* image, kg_detection* out, std::size_t* count) {
        return kg_detect(as_detector(handle), image, out, KG_MAX_DETECTIONS, count);
      },
      buffer, array, offset, width, height, row_stride, doubles, ints);
}

JNIEXPORT jlong JNICALL Java_org_keygraph_Native_trackerCreate(JNIEnv* env, jclass, jlong detector,
                                                               jint detect_interval,
                                                               jdouble min_correlation,
                                                               jint max_tracks, jdouble smoothing) {
  const kg_tracker_options options{detect_interval, min_correlation, max_tracks, smoothing};
  kg_tracker* tracker = nullptr;
  if (const kg_status s = kg_tracker_create(as_detector(detector), &options, &tracker); s != KG_OK)
    throw_status(env, s);
  return as_handle(tracker);
}

JNIEXPORT void JNICALL Java_org_keygraph_Native_trackerDestroy(JNIEnv*, jclass, jlong handle) {
  kg_tracker_destroy(as_tracker(handle));
}

JNIEXPORT jboolean JNICALL Java_org_keygraph_Native_trackerCanTrack(JNIEnv*, jclass, jlong handle) {
  return kg_tracker_can_track(as_tracker(handle)) != 0 ? JNI_TRUE : JNI_FALSE;
}

JNIEXPORT void JNICALL Java_org_keygraph_Native_trackerReset(JNIEnv*, jclass, jlong handle) {
  kg_tracker_reset(as_tracker(handle));
}

JNIEXPORT jint JNICALL Java_org_keygraph_Native_trackerProcess(
    JNIEnv* env, jclass, jlong handle, jobject buffer, jbyteArray array, jint offset, jint width,
    jint height, jint row_stride, jdoubleArray doubles, jintArray ints) {
  return run_frame(
      env,
      [handle](const kg_image* image, kg_detection* out, std::size_t* count) {
        return kg_tracker_process(as_tracker(handle), image, out, KG_MAX_DETECTIONS, count);
      },
      buffer, array, offset, width, height, row_stride, doubles, ints);
}

}  // extern "C"
