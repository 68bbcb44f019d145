import type { Session } from "../lib/session";
import type { StatusBar } from "../lib/statusbar";

export interface PageContext {
  session: Session;
  root: HTMLElement;
  status: StatusBar;
  /** Route parameters after the page name: #/tracks/12 gives ["12"]. */
  params: string[];
  /** The query after the route: #/playback?t=1700000000&alarm=3 gives t and alarm. */
  query: URLSearchParams;
}

export interface Page {
  unmount?(): void;
}

export type PageFactory = (ctx: PageContext) => Page | Promise<Page>;
