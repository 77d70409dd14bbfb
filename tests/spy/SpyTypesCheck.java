// lcm-spy's type database must know every snapnav type, and decode a log
// written by a C++ process. Usage: java SpyTypesCheck JAR LOG
import java.util.Enumeration;
import java.util.jar.JarEntry;
import java.util.jar.JarFile;
import lcm.logging.Log;
import lcm.spy.LCMTypeDatabase;

public class SpyTypesCheck {
  public static void main(String[] args) throws Exception {
    LCMTypeDatabase db = new LCMTypeDatabase();
    int types = 0;
    try (JarFile jar = new JarFile(args[0])) {
      for (Enumeration<JarEntry> e = jar.entries(); e.hasMoreElements();) {
        String name = e.nextElement().getName();
        if (!name.startsWith("snapnav/") || !name.endsWith(".class")) continue;
        Class<?> c = Class.forName(name.replace('/', '.').replace(".class", ""));
        long fp = c.getField("LCM_FINGERPRINT").getLong(null);
        if (db.getClassByFingerprint(fp) != c) throw new AssertionError("lcm-spy does not know " + c.getName());
        ++types;
      }
    }
    if (types < 10) throw new AssertionError("only " + types + " snapnav types in " + args[0]);

    Log log = new Log(args[1], "r");
    int frames = 0;
    while (true) {
      Log.Event ev;
      try {
        ev = log.readNext();
      } catch (java.io.EOFException eof) {
        break;
      }
      long fp = java.nio.ByteBuffer.wrap(ev.data, 0, 8).getLong();
      Class<?> c = db.getClassByFingerprint(fp);
      if (c == null) throw new AssertionError("no type for channel " + ev.channel);
      Object msg = c.getConstructor(byte[].class).newInstance((Object) ev.data);
      snapnav.omni_frame_t f = (snapnav.omni_frame_t) msg;
      if (f.width != 100 || f.data.length != 100) throw new AssertionError("bad frame width " + f.width);
      ++frames;
    }
    if (frames != 3) throw new AssertionError("decoded " + frames + " frames, expected 3");
    System.out.println("PASS: lcm-spy knows " + types + " snapnav types and decoded " + frames + " C++ frames");
  }
}
