/* A minimal XDND drag source for the window tests: drops files on an X window, as a file
 * manager would, so that a test can check what the app does with a dropped scene file
 * (Xvfb has no desktop to drag from).
 *
 *   xdnd_drop WINDOW_ID X Y FILE...
 *
 * WINDOW_ID is the target's top-level window (decimal or 0x hex, as xdotool prints it);
 * X Y a point inside it (window pixels). The files go as one text/uri-list of file:// URIs
 * (absolute paths; a relative one is taken from the working directory).
 *
 * The protocol (XDND version 5, freedesktop.org's "Drag-and-Drop Protocol for the X Window
 * System"): the source owns the XdndSelection; it sends the target XdndEnter (its version
 * and the offered type), XdndPosition (the pointer in root coordinates, the copy action)
 * and waits for XdndStatus; when the target accepts it sends XdndDrop; the target then
 * converts XdndSelection to text/uri-list, which the source answers on SelectionRequest by
 * writing the list to the requestor's property and sending SelectionNotify; the target
 * ends with XdndFinished. Exit 0 once XdndFinished says the drop was accepted; 1 on a
 * refusal or a timeout (10 s per step), with a line on stderr saying which step.
 */
#include <X11/Xatom.h>
#include <X11/Xlib.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/select.h>
#include <unistd.h>

static Display* dpy;
static Window source, target;
static Atom a_aware, a_enter, a_position, a_status, a_drop, a_finished, a_leave, a_selection,
    a_copy, a_uri_list;
static char* uri_list;

static int fail(const char* what) {
  fprintf(stderr, "xdnd_drop: %s\n", what);
  return 1;
}

/* one XDND client message from the source to the target */
static void send_xdnd(Atom type, long l1, long l2, long l3, long l4) {
  XEvent ev;
  memset(&ev, 0, sizeof ev);
  ev.xclient.type = ClientMessage;
  ev.xclient.display = dpy;
  ev.xclient.window = target;
  ev.xclient.message_type = type;
  ev.xclient.format = 32;
  ev.xclient.data.l[0] = (long)source;
  ev.xclient.data.l[1] = l1;
  ev.xclient.data.l[2] = l2;
  ev.xclient.data.l[3] = l3;
  ev.xclient.data.l[4] = l4;
  XSendEvent(dpy, target, False, NoEventMask, &ev);
  XFlush(dpy);
}

/* answer a conversion of XdndSelection: the uri list as text/uri-list, or a refusal */
static void answer_selection_request(const XSelectionRequestEvent* rq) {
  XEvent reply;
  memset(&reply, 0, sizeof reply);
  reply.xselection.type = SelectionNotify;
  reply.xselection.display = rq->display;
  reply.xselection.requestor = rq->requestor;
  reply.xselection.selection = rq->selection;
  reply.xselection.target = rq->target;
  reply.xselection.time = rq->time;
  reply.xselection.property = None;
  if (rq->selection == a_selection && rq->target == a_uri_list && rq->property != None) {
    XChangeProperty(dpy, rq->requestor, rq->property, a_uri_list, 8, PropModeReplace,
                    (const unsigned char*)uri_list, (int)strlen(uri_list));
    reply.xselection.property = rq->property;
  }
  XSendEvent(dpy, rq->requestor, False, NoEventMask, &reply);
  XFlush(dpy);
}

/* waits for a client message of `type` to the source, answering selection requests on the
 * way; returns 0 with it in *out, or 1 after `seconds` */
static int wait_for(Atom type, XClientMessageEvent* out, int seconds) {
  const int fd = ConnectionNumber(dpy);
  int waited_ms = 0;
  for (;;) {
    while (XPending(dpy)) {
      XEvent ev;
      XNextEvent(dpy, &ev);
      if (ev.type == SelectionRequest) answer_selection_request(&ev.xselectionrequest);
      else if (ev.type == ClientMessage && ev.xclient.message_type == type) {
        *out = ev.xclient;
        return 0;
      }
    }
    if (waited_ms >= seconds * 1000) return 1;
    fd_set set;
    FD_ZERO(&set);
    FD_SET(fd, &set);
    struct timeval tv = {0, 50000};
    select(fd + 1, &set, NULL, NULL, &tv);
    waited_ms += 50;
  }
}

/* file:// URI of a path, percent-encoding what a URI may not hold */
static void append_uri(char** list, size_t* len, size_t* cap, const char* path) {
  char abs[PATH_MAX];
  if (path[0] == '/') snprintf(abs, sizeof abs, "%s", path);
  else {
    char cwd[PATH_MAX];
    if (!getcwd(cwd, sizeof cwd)) cwd[0] = 0;
    snprintf(abs, sizeof abs, "%s/%s", cwd, path);
  }
  const size_t need = *len + 3 * strlen(abs) + 16;
  if (need > *cap) {
    *cap = 2 * need;
    *list = realloc(*list, *cap);
  }
  *len += (size_t)sprintf(*list + *len, "file://");
  for (const unsigned char* c = (const unsigned char*)abs; *c; ++c) {
    if ((*c >= 'a' && *c <= 'z') || (*c >= 'A' && *c <= 'Z') || (*c >= '0' && *c <= '9') ||
        strchr("/-_.~", *c))
      (*list)[(*len)++] = (char)*c;
    else *len += (size_t)sprintf(*list + *len, "%%%02X", *c);
  }
  *len += (size_t)sprintf(*list + *len, "\r\n");
}

int main(int argc, char** argv) {
  if (argc < 5) {
    fprintf(stderr, "usage: xdnd_drop WINDOW_ID X Y FILE...\n");
    return 2;
  }
  target = (Window)strtoul(argv[1], NULL, 0);
  const int x = atoi(argv[2]), y = atoi(argv[3]);
  size_t len = 0, cap = 0;
  uri_list = NULL;
  for (int i = 4; i < argc; ++i) append_uri(&uri_list, &len, &cap, argv[i]);
  uri_list[len] = 0;

  /* an X server now and then refuses a connection the next attempt gets (Xvfb in sandboxed
     VMs): a few tries before giving up */
  for (int attempt = 0; attempt < 5 && !(dpy = XOpenDisplay(NULL)); ++attempt) usleep(100000u << attempt);
  if (!dpy) return fail("cannot open the display");
  a_aware = XInternAtom(dpy, "XdndAware", False);
  a_enter = XInternAtom(dpy, "XdndEnter", False);
  a_position = XInternAtom(dpy, "XdndPosition", False);
  a_status = XInternAtom(dpy, "XdndStatus", False);
  a_drop = XInternAtom(dpy, "XdndDrop", False);
  a_finished = XInternAtom(dpy, "XdndFinished", False);
  a_leave = XInternAtom(dpy, "XdndLeave", False);
  a_selection = XInternAtom(dpy, "XdndSelection", False);
  a_copy = XInternAtom(dpy, "XdndActionCopy", False);
  a_uri_list = XInternAtom(dpy, "text/uri-list", False);

  /* the target must say it takes drops, and which protocol version */
  Atom type;
  int format;
  unsigned long items, after;
  unsigned char* data = NULL;
  if (XGetWindowProperty(dpy, target, a_aware, 0, 1, False, AnyPropertyType, &type, &format,
                         &items, &after, &data) != Success || items < 1 || !data)
    return fail("the target window has no XdndAware property: it takes no drops");
  long version = *(long*)data;
  XFree(data);
  if (version > 5) version = 5;

  /* an unmapped window of ours owns the selection and receives the target's replies */
  const Window root = DefaultRootWindow(dpy);
  source = XCreateSimpleWindow(dpy, root, 0, 0, 1, 1, 0, 0, 0);
  XSetSelectionOwner(dpy, a_selection, source, CurrentTime);
  if (XGetSelectionOwner(dpy, a_selection) != source) return fail("cannot own XdndSelection");

  /* the pointer over the target, in root coordinates */
  int rx = 0, ry = 0;
  Window child;
  XTranslateCoordinates(dpy, target, root, x, y, &rx, &ry, &child);

  send_xdnd(a_enter, version << 24, (long)a_uri_list, None, None);
  send_xdnd(a_position, 0, ((long)rx << 16) | (ry & 0xffff), CurrentTime, (long)a_copy);
  XClientMessageEvent msg;
  if (wait_for(a_status, &msg, 10)) return fail("no XdndStatus from the target after XdndPosition");
  if (!(msg.data.l[1] & 1)) {
    send_xdnd(a_leave, 0, 0, 0, 0);
    return fail("the target refused the drop (XdndStatus without accept)");
  }
  send_xdnd(a_drop, 0, CurrentTime, 0, 0);
  if (wait_for(a_finished, &msg, 10)) return fail("no XdndFinished from the target after XdndDrop");
  /* the spec's accept flag is bit 0 of l[1]; GLFW 3.3 puts there the byte count of the data
     it read (0 when it read none), whose bit 0 is the path's length parity: any nonzero value
     is an accepted drop */
  if (version >= 5 && msg.data.l[1] == 0) return fail("the target finished without accepting the drop");
  printf("xdnd_drop: dropped %s", uri_list);
  XDestroyWindow(dpy, source);
  XCloseDisplay(dpy);
  free(uri_list);
  return 0;
}
