// gst_rtx_pipeline: gst-launch-1.0 for an rtpbin with RFC 4588
// retransmission, system (b) of `bench_video --loss` (docs/video.md).
//
// gst-launch cannot answer rtpbin's `request-aux-sender` and
// `request-aux-receiver` signals, which put rtprtxsend / rtprtxreceive in an
// RTP session (GStreamer's examples server-rtpaux.c and client-rtpaux.c in
// gst-plugins-good show them); this program parses a gst-launch pipeline
// description, answers those signals and `request-pt-map`, and runs it.
//
//   gst_rtx_pipeline --send|--receive [--pt 96] [--rtx-pt 97] [--session KEY=VALUE]... PIPELINE...
//
// The pipeline holds one rtpbin (session 0: its *_0 pads linked). --send: the
// session's aux sender is rtprtxsend (payload-type map pt -> rtx-pt);
// --receive: its aux receiver is rtprtxreceive (same map), and request-pt-map
// answers H.264 at 90 kHz for pt and "rtx" for rtx-pt. --session sets a
// property of the internal RTP session (rtpbin's get-internal-session), e.g.
// rtcp-min-interval (ns) so that NACKs are not held back by the RTCP interval. Runs until EOS, an
// error (exit 1) or SIGTERM/SIGINT (exit 0); then prints the retransmission
// element's counters as one JSON line on stderr (stdout may carry video):
//   {"rtx_requests":N,"rtx_packets":N,"rtx_assoc_packets":N}
// Exit 2 on bad arguments or a pipeline that does not parse.
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <utility>
#include <vector>

#include <glib-unix.h>
#include <gst/gst.h>

namespace {

struct App {
  bool send = false;
  guint pt = 96, rtx_pt = 97;
  GstElement* rtx = nullptr;  // the rtprtxsend / rtprtxreceive made for session 0 (a reference)
  GMainLoop* loop = nullptr;
  int status = 0;
  int rtpbins = 0;
  GstElement* rtpbin = nullptr;
  std::vector<std::pair<std::string, std::string>> session_props;  // --session KEY=VALUE
};

GstStructure* ptMap(const App& a) {
  const std::string key = std::to_string(a.pt);
  return gst_structure_new("application/x-rtp-pt-map", key.c_str(), G_TYPE_UINT, a.rtx_pt, nullptr);
}

// A bin around one retransmission element with the ghost pads rtpbin links: sink_<id>, src_<id>.
GstElement* auxBin(App& a, const char* factory, guint session) {
  if (session != 0) return nullptr;
  GstElement* rtx = gst_element_factory_make(factory, nullptr);
  if (rtx == nullptr) {
    std::fprintf(stderr, "gst_rtx_pipeline: no element %s (gstreamer1.0-plugins-good)\n", factory);
    return nullptr;
  }
  GstStructure* map = ptMap(a);
  g_object_set(rtx, "payload-type-map", map, nullptr);
  gst_structure_free(map);
  GstElement* bin = gst_bin_new(nullptr);
  gst_bin_add(GST_BIN(bin), rtx);
  for (const char* dir : {"sink", "src"}) {
    GstPad* pad = gst_element_get_static_pad(rtx, dir);
    const std::string name = std::string(dir) + "_" + std::to_string(session);
    gst_element_add_pad(bin, gst_ghost_pad_new(name.c_str(), pad));
    gst_object_unref(pad);
  }
  if (a.rtx != nullptr) gst_object_unref(a.rtx);
  a.rtx = GST_ELEMENT(gst_object_ref(rtx));
  return bin;
}

GstElement* onAuxSender(GstElement*, guint session, gpointer data) {
  return auxBin(*static_cast<App*>(data), "rtprtxsend", session);
}

GstElement* onAuxReceiver(GstElement*, guint session, gpointer data) {
  return auxBin(*static_cast<App*>(data), "rtprtxreceive", session);
}

GstCaps* onPtMap(GstElement*, guint session, guint pt, gpointer data) {
  const App& a = *static_cast<App*>(data);
  if (session != 0 || (pt != a.pt && pt != a.rtx_pt)) return nullptr;
  return gst_caps_new_simple("application/x-rtp", "media", G_TYPE_STRING, "video", "clock-rate", G_TYPE_INT, 90000,
                             "encoding-name", G_TYPE_STRING, pt == a.pt ? "H264" : "rtx", "payload", G_TYPE_INT,
                             static_cast<int>(pt), nullptr);
}

// rtpbin asks for its aux elements when a session is made, i.e. while
// gst_parse_launch links its pads: the handlers go on as soon as it is added
// to its bin (an emission hook of GstBin's element-added), before any link.
gboolean onElementAdded(GSignalInvocationHint*, guint n, const GValue* params, gpointer data) {
  if (n < 2) return TRUE;
  auto* e = GST_ELEMENT(g_value_get_object(&params[1]));
  GstElementFactory* f = e != nullptr ? gst_element_get_factory(e) : nullptr;
  if (f == nullptr || std::strcmp(GST_OBJECT_NAME(f), "rtpbin") != 0) return TRUE;
  App& a = *static_cast<App*>(data);
  if (a.send) {
    g_signal_connect(e, "request-aux-sender", G_CALLBACK(onAuxSender), &a);
  } else {
    g_signal_connect(e, "request-aux-receiver", G_CALLBACK(onAuxReceiver), &a);
    g_signal_connect(e, "request-pt-map", G_CALLBACK(onPtMap), &a);
  }
  ++a.rtpbins;
  a.rtpbin = e;
  return TRUE;
}

gboolean onBus(GstBus*, GstMessage* m, gpointer data) {
  App& a = *static_cast<App*>(data);
  switch (GST_MESSAGE_TYPE(m)) {
    case GST_MESSAGE_EOS: g_main_loop_quit(a.loop); break;
    case GST_MESSAGE_ERROR: {
      GError* e = nullptr;
      gchar* debug = nullptr;
      gst_message_parse_error(m, &e, &debug);
      std::fprintf(stderr, "gst_rtx_pipeline: error from %s: %s\n", GST_OBJECT_NAME(m->src), e->message);
      g_clear_error(&e);
      g_free(debug);
      a.status = 1;
      g_main_loop_quit(a.loop);
      break;
    }
    default: break;
  }
  return TRUE;
}

gboolean onSignal(gpointer data) {
  g_main_loop_quit(static_cast<App*>(data)->loop);
  return G_SOURCE_REMOVE;
}

guint counter(GstElement* e, const char* name) {
  if (e == nullptr || g_object_class_find_property(G_OBJECT_GET_CLASS(e), name) == nullptr) return 0;
  guint v = 0;
  g_object_get(e, name, &v, nullptr);
  return v;
}

int usage(const char* why) {
  std::fprintf(stderr, "gst_rtx_pipeline: %s\nusage: gst_rtx_pipeline --send|--receive [--pt 96] [--rtx-pt 97] [--session KEY=VALUE]... PIPELINE...\n",
               why);
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  gst_init(&argc, &argv);
  App a;
  int i = 1;
  bool role = false;
  for (; i < argc && std::strncmp(argv[i], "--", 2) == 0; ++i) {
    const std::string k = argv[i];
    if (k == "--send" || k == "--receive") {
      a.send = k == "--send";
      role = true;
    } else if (k == "--session" && i + 1 < argc) {
      const std::string kv = argv[++i];
      const auto eq = kv.find('=');
      if (eq == std::string::npos || eq == 0) return usage("--session takes KEY=VALUE");
      a.session_props.emplace_back(kv.substr(0, eq), kv.substr(eq + 1));
    } else if ((k == "--pt" || k == "--rtx-pt") && i + 1 < argc) {
      const long v = std::strtol(argv[++i], nullptr, 10);
      if (v < 0 || v > 127) return usage("payload types are 0-127");
      (k == "--pt" ? a.pt : a.rtx_pt) = static_cast<guint>(v);
    } else {
      return usage(("unknown option " + k).c_str());
    }
  }
  if (!role) return usage("--send or --receive");
  if (i >= argc) return usage("no pipeline");
  g_type_class_unref(g_type_class_ref(GST_TYPE_BIN));
  g_signal_add_emission_hook(g_signal_lookup("element-added", GST_TYPE_BIN), 0, onElementAdded, &a, nullptr);
  GError* err = nullptr;
  GstElement* pipeline = gst_parse_launchv(const_cast<const gchar**>(argv + i), &err);
  if (pipeline == nullptr || err != nullptr) {
    std::fprintf(stderr, "gst_rtx_pipeline: pipeline: %s\n", err ? err->message : "does not parse");
    return 2;
  }
  if (a.rtpbins != 1) return usage("the pipeline must hold one rtpbin");
  if (a.rtx == nullptr) return usage("rtpbin made no RTP session 0 (link its *_0 pads)");
  if (!a.session_props.empty()) {
    GObject* session = nullptr;
    g_signal_emit_by_name(a.rtpbin, "get-internal-session", 0u, &session);
    if (session == nullptr) return usage("rtpbin has no internal session 0");
    for (const auto& [k, v] : a.session_props) {
      if (g_object_class_find_property(G_OBJECT_GET_CLASS(session), k.c_str()) == nullptr)
        return usage(("the RTP session has no property " + k).c_str());
      gst_util_set_object_arg(session, k.c_str(), v.c_str());
    }
    g_object_unref(session);
  }
  a.loop = g_main_loop_new(nullptr, FALSE);
  GstBus* bus = gst_element_get_bus(pipeline);
  gst_bus_add_watch(bus, onBus, &a);
  g_unix_signal_add(SIGTERM, onSignal, &a);
  g_unix_signal_add(SIGINT, onSignal, &a);
  if (gst_element_set_state(pipeline, GST_STATE_PLAYING) == GST_STATE_CHANGE_FAILURE) {
    std::fprintf(stderr, "gst_rtx_pipeline: the pipeline does not start\n");
    a.status = 1;
  } else {
    g_main_loop_run(a.loop);
  }
  std::fprintf(stderr, "{\"rtx_requests\":%u,\"rtx_packets\":%u,\"rtx_assoc_packets\":%u}\n",
               counter(a.rtx, "num-rtx-requests"), counter(a.rtx, "num-rtx-packets"),
               counter(a.rtx, "num-rtx-assoc-packets"));
  gst_element_set_state(pipeline, GST_STATE_NULL);
  if (a.rtx != nullptr) gst_object_unref(a.rtx);
  gst_bus_remove_watch(bus);
  gst_object_unref(bus);
  gst_object_unref(pipeline);
  g_main_loop_unref(a.loop);
  return a.status;
}
