// DisplayCheck: opens the display, then runs a Java GUI's main class in this JVM (lcm-spy,
// lcm-logplayer-gui, SpyReport). A display that cannot be opened (DISPLAY unset, wrong, refused) is
// one line naming it and exit status 1, instead of AWT's stack trace from deep inside the GUI.
// `./snapnav spy` and `./snapnav logplayer-gui` start every GUI through it.
//   java -cp ... DisplayCheck MAIN-CLASS [ARGS...]
//   java -cp ... DisplayCheck --only          (the check alone: exit status 0 when the display opens)
import java.awt.GraphicsEnvironment;
import java.lang.reflect.InvocationTargetException;
import java.util.Arrays;

public class DisplayCheck {
  // What is wrong with the display, null when it opens.
  static String problem() {
    String display = System.getenv("DISPLAY");
    try {
      if (GraphicsEnvironment.isHeadless()) return "Java runs headless (no DISPLAY, or java.awt.headless set)";
      if (GraphicsEnvironment.getLocalGraphicsEnvironment().getScreenDevices().length == 0) return "it has no screen";
      return null;
    } catch (Throwable e) {  // AWTError, HeadlessException, a missing native library
      String what = String.valueOf(e.getMessage());
      int newline = what.indexOf('\n');
      what = (newline < 0 ? what : what.substring(0, newline)).trim();
      return what.endsWith(".") ? what.substring(0, what.length() - 1) : what;
    }
  }

  public static void main(String[] args) throws Throwable {
    if (args.length < 1) {
      System.err.println("usage: DisplayCheck MAIN-CLASS [ARGS...] | --only");
      System.exit(2);
    }
    String problem = problem();
    if (problem != null) {
      String display = System.getenv("DISPLAY");
      System.err.println("snapnav: error: cannot open the display "
                         + (display == null || display.isEmpty() ? "(DISPLAY is not set)" : "'" + display + "'") + ": "
                         + problem + ". Use the machine's desktop, ssh -X, or Xvfb (xvfb-run).");
      System.exit(1);
    }
    if (args[0].equals("--only")) System.exit(0);
    try {
      Class.forName(args[0]).getMethod("main", String[].class).invoke(null, (Object) Arrays.copyOfRange(args, 1, args.length));
    } catch (InvocationTargetException e) {
      throw e.getCause();
    }
  }
}
