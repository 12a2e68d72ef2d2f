// The links every inspector page carries in its header: runs, compare, leaderboard, editor.

import { pageUrl } from "./api.js";
import { el } from "./panel.js";

const PAGES = [["runs", "/runs"], ["compare", "/compare"], ["leaderboard", "/leaderboard"], ["editor", "/editor"]];

export function navLinks(current) {
  return el("nav", { class: "pages" }, PAGES.map(([name, path]) =>
    el("a", { href: pageUrl(path), class: name === current ? "current" : "" }, name)));
}
